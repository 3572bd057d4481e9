#include "drivers/hapticsim/sim_device.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace visvol::hapticsim {
namespace {

using haptic::MessageKind;
using haptic::NmtState;
using haptic::norm3;

constexpr double kNsPerS = 1e9;
constexpr double kMmPerM = 1000.0;
constexpr double kSubstepS = 0.00025;  // physics substep
constexpr double kMaxStepS = 0.02;     // longer gaps (a stalled process) are cut short
constexpr double kStickSpeedMPerS = 1e-6;
constexpr double kNPerA = 0.5;  // motor force constant, for reported currents
constexpr double kTemperatureHysteresisC = 10.0;

double sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// The next time a periodic frame is due: one period on, or one period from now
// when the schedule fell behind (after a stall or a quiet state).
std::int64_t next_due(std::int64_t due_ns, std::int64_t period_ns, std::int64_t now_ns) {
  due_ns += period_ns;
  return due_ns <= now_ns ? now_ns + period_ns : due_ns;
}

const haptic::EmergencySpec* emergency_for_bit(std::uint16_t fault_bit) {
  for (const haptic::EmergencySpec& e : haptic::kEmergencies) {
    if (e.fault_bit == fault_bit && fault_bit != 0) return &e;
  }
  return nullptr;
}

}  // namespace

Status SimDevice::validate(const SimConfig& c) {
  const auto bad = [](const std::string& field, const std::string& why) {
    return invalid_argument("simulated device: " + field + " " + why);
  };
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (c.node_id < haptic::kMinNodeId || c.node_id > haptic::kMaxNodeId) {
    return bad("node id", std::to_string(c.node_id) + " is outside 1..127");
  }
  if (!positive(c.mass_kg)) return bad("mass", "must be positive (kg)");
  if (!non_negative(c.viscous_n_s_per_m)) return bad("viscous friction", "must be >= 0 (N s/m)");
  if (!non_negative(c.coulomb_n)) return bad("dry friction", "must be >= 0 (N)");
  if (!positive(c.peak_force_n) || c.peak_force_n > 32.0) return bad("peak force", "must lie in (0, 32] N");
  if (!positive(c.encoder_mm) || c.encoder_mm > 10.0) return bad("encoder resolution", "must lie in (0, 10] mm");
  for (const double h : c.workspace_half_mm) {
    if (!positive(h) || h > 320.0) return bad("workspace", "half-sizes must lie in (0, 320] mm");
  }
  if (!non_negative(c.end_stop_n_per_m) || c.end_stop_n_per_m > 1e5)
    return bad("end stop stiffness", "must lie in [0, 1e5] N/m");
  if (!non_negative(c.hand_stiffness_n_per_m) || c.hand_stiffness_n_per_m > 1e4)
    return bad("hand stiffness", "must lie in [0, 1e4] N/m");
  if (!non_negative(c.hand_damping_n_s_per_m) || c.hand_damping_n_s_per_m > 100.0)
    return bad("hand damping", "must lie in [0, 100] N s/m");
  if (c.command_timeout_ns < 1'000'000) return bad("command watchdog", "must be at least 1 ms");
  if (c.heartbeat_period_ns < 1'000'000) return bad("heartbeat period", "must be at least 1 ms");
  if (c.status_period_ns < 1'000'000) return bad("status period", "must be at least 1 ms");
  if (c.boot_delay_ns < 0) return bad("boot delay", "must be >= 0");
  if (!std::isfinite(c.ambient_c) || !non_negative(c.heating_c_per_n2) || !positive(c.thermal_time_s) ||
      !std::isfinite(c.over_temperature_c) || c.over_temperature_c <= c.ambient_c) {
    return bad("thermal model", "needs finite values, a positive time constant and a limit above ambient");
  }
  if (!(c.drop_fraction >= 0.0 && c.drop_fraction <= 1.0)) return bad("drop fraction", "must lie in [0, 1]");
  return Status::ok_status();
}

Result<SimDevice> SimDevice::create(const SimConfig& config, can::CanBus& bus, std::int64_t start_ns) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  return SimDevice(config, bus, start_ns);
}

SimDevice::SimDevice(const SimConfig& config, can::CanBus& bus, std::int64_t start_ns)
    : config_(config),
      bus_(&bus),
      rng_(config.seed),
      power_on_at_ns_(start_ns + config.boot_delay_ns),
      last_step_ns_(start_ns),
      temperature_c_(config.ambient_c) {}

std::array<double, 3> SimDevice::position_mm() const {
  std::array<double, 3> mm{};
  for (std::size_t i = 0; i < 3; ++i) mm[i] = std::round(pos_m_[i] * kMmPerM / config_.encoder_mm) * config_.encoder_mm;
  return mm;
}

bool SimDevice::roll(double probability) {
  if (probability <= 0.0) return false;
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < probability;
}

void SimDevice::step(std::int64_t now_ns) {
  const double dt_s = std::clamp(static_cast<double>(now_ns - last_step_ns_) / kNsPerS, 0.0, kMaxStepS);
  last_step_ns_ = now_ns;
  if (!powered_ && now_ns >= power_on_at_ns_) power_on(now_ns);
  receive(now_ns);
  end_injections(now_ns);
  update_motor(now_ns, dt_s);
  integrate(dt_s);
  transmit(now_ns);
}

void SimDevice::power_on(std::int64_t now_ns) {
  powered_ = true;
  ++counters_.boots;
  nmt_ = NmtState::boot_up;
  position_sequence_ = 0;
  status_sequence_ = 0;
  have_command_ = false;
  command_ = haptic::CommandMsg{};
  watchdog_tripped_ = false;
  fault_bits_ = 0;
  injected_fault_bit_ = 0;
  send_heartbeat();  // the boot-up message
  nmt_ = NmtState::pre_operational;
  next_heartbeat_ns_ = now_ns + config_.heartbeat_period_ns;
  next_status_ns_ = now_ns;
}

void SimDevice::receive(std::int64_t now_ns) {
  const std::uint32_t command_id = haptic::frame_id(MessageKind::command, config_.node_id);
  bool capped = false;
  can::drain(*bus_, batch_, 256, &capped, [&](const can::CanFrame& f) {
    if (!powered_ || now_ns < silent_until_ns_ || bus_off_) {
      ++counters_.rx_ignored;
      return;
    }
    if (roll(config_.drop_fraction)) {
      ++counters_.rx_dropped;
      return;
    }
    haptic::Message m;
    const haptic::DecodeError error = haptic::decode(f, m);
    if (error != haptic::DecodeError::ok) {
      if (f.is_standard_data() && (f.id == command_id || f.id == haptic::kNmtId)) ++counters_.malformed;
      return;
    }
    if (m.kind == MessageKind::nmt && (m.nmt.node == 0 || m.nmt.node == config_.node_id)) {
      on_nmt(m.nmt, now_ns);
    } else if (m.kind == MessageKind::command && m.node == config_.node_id && nmt_ == NmtState::operational) {
      if (have_command_) {
        counters_.command_gaps += static_cast<std::uint8_t>(m.command.sequence - command_.sequence - 1);
      }
      command_ = m.command;
      have_command_ = true;
      last_command_ns_ = now_ns;
      ++counters_.commands;
      if (command_.enable) counters_.max_commanded_n = std::max(counters_.max_commanded_n, norm3(command_.force_n));
      counters_.last_command_n = norm3(command_.force_n);
      counters_.last_command_enabled = command_.enable;
    }
  });
}

void SimDevice::on_nmt(const haptic::NmtMsg& nmt, std::int64_t now_ns) {
  ++counters_.nmt_commands;
  const NmtState before = nmt_;
  switch (nmt.command) {
    case haptic::NmtCommand::start: nmt_ = NmtState::operational; break;
    case haptic::NmtCommand::stop: nmt_ = NmtState::stopped; break;
    case haptic::NmtCommand::enter_pre_operational: nmt_ = NmtState::pre_operational; break;
    case haptic::NmtCommand::reset_node: inject_reboot(now_ns, 50'000'000); return;
    case haptic::NmtCommand::reset_communication: inject_reboot(now_ns, 0); return;
  }
  if (nmt_ == before) return;
  if (nmt_ == NmtState::operational) {
    have_command_ = false;  // forces only from commands received from now on
    if (counters_.first_operational_ns < 0) counters_.first_operational_ns = now_ns;
  }
  send_heartbeat();  // tell the console at once rather than at the next period
}

void SimDevice::end_injections(std::int64_t now_ns) {
  if (bus_off_ && now_ns >= bus_off_until_ns_) {
    bus_off_ = false;
    can::CanFrame restarted;
    restarted.flags = can::CanFrame::kError;
    restarted.id = can::err::kRestarted;
    restarted.len = 8;
    send(restarted, false);
  }
  if (injected_fault_bit_ != 0 && now_ns >= injected_fault_until_ns_) {
    fault_bits_ = static_cast<std::uint16_t>(fault_bits_ & ~injected_fault_bit_);
    injected_fault_bit_ = 0;
    if (fault_bits_ == 0 && powered_) send_emergency(0x0000, haptic::kAxisNone);
  }
}

void SimDevice::update_motor(std::int64_t now_ns, double dt_s) {
  // Motor temperature: first order toward ambient + heating x F^2.
  const double force_n = norm3(motor_force_n_);
  const double target_c = config_.ambient_c + config_.heating_c_per_n2 * force_n * force_n;
  temperature_c_ += (1.0 - std::exp(-dt_s / config_.thermal_time_s)) * (target_c - temperature_c_);
  const bool hot = (fault_bits_ & haptic::kFaultOverTemperature) != 0;
  if (powered_ && !hot && temperature_c_ > config_.over_temperature_c) {
    fault_bits_ |= haptic::kFaultOverTemperature;
    send_emergency(0x4210, 0);
  } else if (hot && injected_fault_bit_ != haptic::kFaultOverTemperature &&
             temperature_c_ < config_.over_temperature_c - kTemperatureHysteresisC) {
    fault_bits_ = static_cast<std::uint16_t>(fault_bits_ & ~haptic::kFaultOverTemperature);
    if (fault_bits_ == 0) send_emergency(0x0000, haptic::kAxisNone);
  }

  const bool operational = powered_ && nmt_ == NmtState::operational;
  const bool command_fresh = have_command_ && now_ns - last_command_ns_ < config_.command_timeout_ns;
  if (operational && have_command_ && !command_fresh && !watchdog_tripped_) {
    watchdog_tripped_ = true;
    ++counters_.watchdog_trips;
  }
  if (command_fresh) watchdog_tripped_ = false;

  motor_force_n_ = {0.0, 0.0, 0.0};
  saturated_ = false;
  if (operational && command_fresh && command_.enable && fault_bits_ == 0) {
    motor_force_n_ = command_.force_n;
    const double magnitude_n = norm3(motor_force_n_);
    if (magnitude_n > config_.peak_force_n) {
      for (double& f : motor_force_n_) f *= config_.peak_force_n / magnitude_n;
      saturated_ = true;
      ++counters_.saturated_steps;
    }
  }
  const double applied_n = norm3(motor_force_n_);
  if (applied_n > 0.0) ++counters_.force_steps;
  counters_.max_force_n = std::max(counters_.max_force_n, applied_n);
  if (operational) ++counters_.operational_steps;
}

void SimDevice::integrate(double dt_s) {
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt_s / kSubstepS)));
  const double h = dt_s / substeps;
  for (int s = 0; s < substeps; ++s) {
    for (std::size_t i = 0; i < 3; ++i) {
      double& x = pos_m_[i];
      double& v = vel_m_per_s_[i];
      const double half_m = config_.workspace_half_mm[i] / kMmPerM;
      double drive = motor_force_n_[i] - config_.viscous_n_s_per_m * v;
      if (hand_.holding) {
        drive +=
            config_.hand_stiffness_n_per_m * (hand_.target_mm[i] / kMmPerM - x) - config_.hand_damping_n_s_per_m * v;
      }
      if (x > half_m) drive -= config_.end_stop_n_per_m * (x - half_m);
      if (x < -half_m) drive -= config_.end_stop_n_per_m * (x + half_m);
      // Dry friction: stick while the drive stays below it, never reverse the motion.
      if (std::fabs(v) < kStickSpeedMPerS && std::fabs(drive) <= config_.coulomb_n) {
        v = 0.0;
        continue;
      }
      const double friction = -config_.coulomb_n * sign(std::fabs(v) >= kStickSpeedMPerS ? v : drive);
      const double v_next = v + (drive + friction) / config_.mass_kg * h;
      v = (sign(v_next) != sign(v) && v != 0.0 && std::fabs(drive) <= config_.coulomb_n) ? 0.0 : v_next;
      x += v * h;
    }
  }
}

void SimDevice::transmit(std::int64_t now_ns) {
  if (!powered_ || now_ns < silent_until_ns_ || bus_off_) return;
  if (garbage_left_ > 0) {
    send_garbage();
    --garbage_left_;
  }
  if (nmt_ == NmtState::operational) {
    haptic::PositionMsg p;
    p.pos_mm = position_mm();
    p.buttons =
        static_cast<std::uint8_t>((hand_.grasp ? haptic::kButtonGrasp : 0) |
                                  (hand_.clutch ? haptic::kButtonClutch : 0) | (hand_.mode ? haptic::kButtonMode : 0));
    p.sequence = position_sequence_++;
    last_position_frame_ = haptic::encode(p, config_.node_id);
    send(now_ns < freeze_until_ns_ ? frozen_frame_ : last_position_frame_, true);
    if (now_ns >= next_status_ns_) {
      haptic::StatusMsg s;
      s.nmt_state = nmt_;
      s.flags = static_cast<std::uint8_t>((norm3(motor_force_n_) > 0.0 ? haptic::kStatusForceEnabled : 0) |
                                          (watchdog_tripped_ ? haptic::kStatusWatchdog : 0) |
                                          (saturated_ ? haptic::kStatusSaturated : 0));
      s.fault_bits = fault_bits_;
      s.motor_temperature_c = temperature_c_;
      s.sequence = status_sequence_++;
      send(haptic::encode(s, config_.node_id), true);
      next_status_ns_ = next_due(next_status_ns_, config_.status_period_ns, now_ns);
    }
  }
  if (now_ns >= next_heartbeat_ns_) {
    send_heartbeat();
    next_heartbeat_ns_ = next_due(next_heartbeat_ns_, config_.heartbeat_period_ns, now_ns);
  }
}

void SimDevice::send_heartbeat() {
  haptic::HeartbeatMsg hb;
  hb.state = nmt_;
  send(haptic::encode(hb, config_.node_id), true);
}

void SimDevice::send_emergency(std::uint16_t code, std::uint8_t axis) {
  haptic::EmergencyMsg e;
  e.code = code;
  e.axis = axis;
  for (const haptic::EmergencySpec& spec : haptic::kEmergencies) {
    if (spec.code == code) e.error_register = spec.error_register;
  }
  e.temperature_c = temperature_c_;
  if (axis < 3) e.current_a = std::fabs(motor_force_n_[axis]) / kNPerA;
  ++counters_.emergencies;
  send(haptic::encode(e, config_.node_id), true);
}

void SimDevice::send_garbage() {
  // Mostly this device's own identifiers (they pass the console's filters).
  const std::uint32_t own[] = {haptic::frame_id(MessageKind::position, config_.node_id),
                               haptic::frame_id(MessageKind::status, config_.node_id),
                               haptic::frame_id(MessageKind::heartbeat, config_.node_id),
                               haptic::frame_id(MessageKind::emergency, config_.node_id)};
  // Never the console's identifiers (NMT, this node's command): those are not
  // the device's to send, and the console's traffic stays attributable.
  const std::uint32_t command_id = haptic::frame_id(MessageKind::command, config_.node_id);
  can::CanFrame f;
  const std::uint64_t pick = rng_() % 5;
  f.id = pick < 4 ? own[pick] : static_cast<std::uint32_t>(rng_() % (can::kStandardIdMask + 1));
  if (f.id == haptic::kNmtId || f.id == command_id) f.id = own[0];
  f.len = static_cast<std::uint8_t>(rng_() % (can::kMaxDataBytes + 1));
  for (std::uint8_t& b : f.data) b = static_cast<std::uint8_t>(rng_());
  ++counters_.garbage_sent;
  send(f, false);
}

void SimDevice::send(can::CanFrame frame, bool own_frame) {
  if (own_frame && last_step_ns_ < wrong_length_until_ns_) {
    // Any length but the right one.
    frame.len = static_cast<std::uint8_t>((frame.len + 1 + rng_() % can::kMaxDataBytes) % (can::kMaxDataBytes + 1));
  }
  if (!frame.is_error() && roll(config_.drop_fraction)) {
    ++counters_.tx_dropped;
    return;
  }
  if (bus_->send(frame) == Errc::ok) {
    ++counters_.frames_sent;
  } else {
    ++counters_.send_failures;
  }
}

void SimDevice::inject_silence(std::int64_t now_ns, std::int64_t duration_ns) {
  silent_until_ns_ = std::max(silent_until_ns_, now_ns + duration_ns);
}

void SimDevice::inject_wrong_length(std::int64_t now_ns, std::int64_t duration_ns) {
  wrong_length_until_ns_ = std::max(wrong_length_until_ns_, now_ns + duration_ns);
}

void SimDevice::inject_freeze(std::int64_t now_ns, std::int64_t duration_ns) {
  if (now_ns >= freeze_until_ns_) {
    frozen_frame_ = last_position_frame_.len != 0
                        ? last_position_frame_
                        : haptic::encode(haptic::PositionMsg{position_mm(), 0, position_sequence_}, config_.node_id);
  }
  freeze_until_ns_ = std::max(freeze_until_ns_, now_ns + duration_ns);
}

void SimDevice::inject_reboot(std::int64_t now_ns, std::int64_t off_ns) {
  powered_ = false;
  nmt_ = NmtState::boot_up;
  motor_force_n_ = {0.0, 0.0, 0.0};
  power_on_at_ns_ = now_ns + off_ns;
}

void SimDevice::inject_bus_off(std::int64_t now_ns, std::int64_t duration_ns) {
  can::CanFrame off;
  off.flags = can::CanFrame::kError;
  off.id = can::err::kBusOff;
  off.len = 8;
  send(off, false);
  ++counters_.bus_off_events;
  bus_off_ = true;
  bus_off_until_ns_ = now_ns + duration_ns;
}

void SimDevice::inject_emergency(std::int64_t now_ns, std::uint16_t fault_bit, std::int64_t duration_ns) {
  const haptic::EmergencySpec* spec = emergency_for_bit(fault_bit);
  if (spec == nullptr || !powered_) return;
  fault_bits_ |= fault_bit;
  injected_fault_bit_ = fault_bit;
  injected_fault_until_ns_ = now_ns + duration_ns;
  send_emergency(spec->code, 0);
}

}  // namespace visvol::hapticsim
