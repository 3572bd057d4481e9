#include "drivers/haptic/device_driver.hpp"

#include <cmath>
#include <string>

namespace visvol::haptic {
namespace {

constexpr double kNsPerS = 1e9;
// Slack added to the speed limit, mm: one encoder count of noise per axis and more.
constexpr double kJumpSlackMm = 1.0;

bool finite3(const std::array<double, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

}  // namespace

const char* state_name(DeviceState state) {
  switch (state) {
    case DeviceState::boot: return "boot";
    case DeviceState::pre_operational: return "pre-operational";
    case DeviceState::operational: return "operational";
    case DeviceState::fault: return "fault";
  }
  return "invalid";
}

const char* fault_name(FaultReason reason) {
  switch (reason) {
    case FaultReason::none: return "none";
    case FaultReason::bus_off: return "bus-off";
    case FaultReason::heartbeat_lost: return "heartbeat lost";
    case FaultReason::device_fault: return "device fault";
    case FaultReason::position_timeout: return "position timeout";
  }
  return "invalid";
}

Status DeviceDriver::validate(const DriverConfig& c) {
  const auto bad = [](const std::string& field, const std::string& why) {
    return invalid_argument("haptic driver configuration: " + field + " " + why);
  };
  if (c.node_id < kMinNodeId || c.node_id > kMaxNodeId) {
    return bad("node_id", std::to_string(c.node_id) + " is outside 1..127");
  }
  if (c.position_timeout_ns < kPositionPeriodNs || c.position_timeout_ns > 1'000'000'000) {
    return bad("position_timeout_ns", "must lie in 1 ms .. 1 s");
  }
  if (c.heartbeat_timeout_ns <= kHeartbeatPeriodNs || c.heartbeat_timeout_ns > 10'000'000'000) {
    return bad("heartbeat_timeout_ns", "must exceed one heartbeat period (50 ms) and be at most 10 s");
  }
  if (c.nmt_retry_ns < 10'000'000) return bad("nmt_retry_ns", "must be at least 10 ms");
  if (c.fault_clear_ns < kStatusPeriodNs) return bad("fault_clear_ns", "must be at least 10 ms");
  if (!(c.position_limit_mm > 0.0) || c.position_limit_mm > 327.0) {
    return bad("position_limit_mm", "must lie in (0, 327] mm (the int16 range of 0.01 mm)");
  }
  if (!(c.max_speed_mm_per_s > 0.0) || !std::isfinite(c.max_speed_mm_per_s)) {
    return bad("max_speed_mm_per_s", "must be positive and finite");
  }
  if (!(c.max_force_n > 0.0) || c.max_force_n > 32.0) {
    return bad("max_force_n", "must lie in (0, 32] N (the int16 range of 1 mN)");
  }
  if (c.max_frames_per_poll < 16) return bad("max_frames_per_poll", "must be at least 16");
  return Status::ok_status();
}

std::vector<can::CanFilter> DeviceDriver::receive_filters(std::uint8_t node_id) {
  return {{frame_id(MessageKind::heartbeat, node_id), can::kStandardIdMask},
          {frame_id(MessageKind::status, node_id), can::kStandardIdMask},
          {frame_id(MessageKind::position, node_id), can::kStandardIdMask},
          {frame_id(MessageKind::emergency, node_id), can::kStandardIdMask}};
}

Result<DeviceDriver> DeviceDriver::create(const DriverConfig& config, can::CanBus& bus) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  return DeviceDriver(config, bus);
}

void DeviceDriver::poll(std::int64_t now_ns) {
  sample_.fresh = false;
  bool capped = false;
  can::drain(*bus_, batch_, config_.max_frames_per_poll, &capped, [this](const can::CanFrame& f) { on_frame(f); });
  if (capped) ++counters_.capped_polls;
  update_state(now_ns);
}

void DeviceDriver::on_frame(const can::CanFrame& frame) {
  ++counters_.frames;
  if (frame.is_error()) {
    const can::ErrorInfo info = can::classify_error(frame);
    ++counters_.error_frames;
    if (info.bus_off) {
      ++counters_.bus_off;
      bus_off_ = true;
    }
    if (info.restarted) {
      ++counters_.bus_restarts;
      bus_off_ = false;
    }
    return;
  }
  Message m;
  const DecodeError error = decode(frame, m);
  if (error == DecodeError::unknown_id || error == DecodeError::not_data_frame) {
    ++counters_.foreign;
    return;
  }
  if (error != DecodeError::ok) {
    ++counters_.malformed;
    return;
  }
  if (m.node != config_.node_id || !frame_spec(m.kind).from_device) {
    ++counters_.foreign;
    return;
  }
  bus_off_ = false;  // frames arrive: the controller is back on the bus
  switch (m.kind) {
    case MessageKind::heartbeat: on_heartbeat(m); break;
    case MessageKind::status: on_status(m); break;
    case MessageKind::emergency: on_emergency(m); break;
    case MessageKind::position: on_position(m); break;
    case MessageKind::nmt:
    case MessageKind::command: break;  // excluded by from_device above
  }
}

void DeviceDriver::on_heartbeat(const Message& m) {
  ++counters_.heartbeats;
  last_alive_ns_ = m.timestamp_ns;
  if (m.heartbeat.state == NmtState::boot_up) {
    // A (re)booted device: forget what it said before; it is pre-operational now.
    if (seen_device_) ++counters_.device_reboots;
    have_sequence_ = false;
    have_position_ = false;
    report_.emergency_active = false;
    report_.fault_bits = 0;
    clean_since_ns_ = -1;
    nmt_due_ = true;
  }
  seen_device_ = true;
  report_.nmt_state = m.heartbeat.state;
}

void DeviceDriver::on_status(const Message& m) {
  ++counters_.statuses;
  last_alive_ns_ = m.timestamp_ns;
  seen_device_ = true;
  const StatusMsg& s = m.status;
  report_.nmt_state = s.nmt_state;
  report_.fault_bits = s.fault_bits;
  report_.status_flags = s.flags;
  report_.motor_temperature_c = s.motor_temperature_c;
  if (s.fault_bits != 0) {
    clean_since_ns_ = -1;
    return;
  }
  // A lost emergency reset must not latch the fault forever: clean status for
  // fault_clear_ns clears it (a status queued before the emergency may still
  // arrive after it, since the emergency wins arbitration).
  if (clean_since_ns_ < 0) clean_since_ns_ = m.timestamp_ns;
  if (report_.emergency_active && m.timestamp_ns - clean_since_ns_ >= config_.fault_clear_ns) {
    report_.emergency_active = false;
  }
}

void DeviceDriver::on_emergency(const Message& m) {
  ++counters_.emergencies;
  report_.last_emergency = m.emergency;
  report_.emergency_active = m.emergency.error_register != 0;
  clean_since_ns_ = -1;
}

void DeviceDriver::on_position(const Message& m) {
  const PositionMsg& p = m.position;
  if (have_sequence_ && p.sequence == last_sequence_) {
    ++counters_.duplicates;  // a frozen or replayed frame carries no new sample
    return;
  }
  if (have_sequence_) {
    counters_.sequence_gaps += static_cast<std::uint8_t>(p.sequence - last_sequence_ - 1);
  }
  have_sequence_ = true;
  last_sequence_ = p.sequence;

  for (const double c : p.pos_mm) {
    if (std::fabs(c) > config_.position_limit_mm) {
      ++counters_.implausible;
      return;
    }
  }
  if (have_position_) {
    const double dt_s = static_cast<double>(std::max<std::int64_t>(m.timestamp_ns - sample_.timestamp_ns, 0)) / kNsPerS;
    const std::array<double, 3> step_mm = {p.pos_mm[0] - sample_.pos_mm[0], p.pos_mm[1] - sample_.pos_mm[1],
                                           p.pos_mm[2] - sample_.pos_mm[2]};
    if (norm3(step_mm) > config_.max_speed_mm_per_s * dt_s + kJumpSlackMm) {
      ++counters_.implausible;
      return;
    }
  }
  ++counters_.positions;
  have_position_ = true;
  sample_.pos_mm = p.pos_mm;
  sample_.buttons = p.buttons;
  sample_.timestamp_ns = m.timestamp_ns;
  sample_.fresh = true;
}

void DeviceDriver::update_state(std::int64_t now_ns) {
  const bool alive = seen_device_ && now_ns - last_alive_ns_ < config_.heartbeat_timeout_ns;
  const bool positions_fresh = have_position_ && now_ns - sample_.timestamp_ns < config_.position_timeout_ns;
  const bool device_fault = report_.emergency_active || report_.fault_bits != 0;

  DeviceState next = DeviceState::fault;
  FaultReason reason = FaultReason::none;
  if (bus_off_) {
    reason = FaultReason::bus_off;
  } else if (!seen_device_) {
    next = DeviceState::boot;
  } else if (!alive) {
    reason = FaultReason::heartbeat_lost;
  } else if (device_fault) {
    reason = FaultReason::device_fault;
  } else if (report_.nmt_state != NmtState::operational) {
    next = DeviceState::pre_operational;
  } else if (positions_fresh) {
    next = DeviceState::operational;
  } else if (state_ == DeviceState::operational || fault_ == FaultReason::position_timeout) {
    reason = FaultReason::position_timeout;
  } else {
    next = DeviceState::pre_operational;  // operational by report, positions not yet seen
  }

  if (next != state_ || reason != fault_) {
    if (next == DeviceState::fault) ++counters_.faults[static_cast<std::size_t>(reason)];
    if (next == DeviceState::pre_operational) nmt_due_ = true;
    state_ = next;
    fault_ = reason;
  }
  sample_.valid = state_ == DeviceState::operational;
  if (state_ == DeviceState::pre_operational && (nmt_due_ || now_ns - last_nmt_ns_ >= config_.nmt_retry_ns)) {
    send_nmt_start(now_ns);
  }
}

void DeviceDriver::send_nmt_start(std::int64_t now_ns) {
  NmtMsg start;
  start.command = NmtCommand::start;
  start.node = config_.node_id;
  last_nmt_ns_ = now_ns;
  nmt_due_ = false;
  if (bus_->send(encode(start)) == Errc::ok) {
    ++counters_.nmt_sent;
  } else {
    ++counters_.send_failures;
  }
}

Errc DeviceDriver::command(const std::array<double, 3>& force_n, bool enable) {
  if (state_ == DeviceState::boot || (state_ == DeviceState::fault && fault_ == FaultReason::bus_off)) {
    return Errc::state;
  }
  CommandMsg c;
  c.sequence = command_sequence_++;
  if (state_ == DeviceState::operational && enable) {
    if (!finite3(force_n)) {
      ++counters_.rejected_commands;
    } else {
      c.force_n = force_n;
      const double magnitude_n = norm3(force_n);
      if (magnitude_n > config_.max_force_n) {
        const double k = config_.max_force_n / magnitude_n;
        for (double& f : c.force_n) f *= k;
        ++counters_.clamped_commands;
      }
      c.enable = true;
    }
  }
  last_command_ = c;
  const Errc result = bus_->send(encode(c, config_.node_id));
  if (result == Errc::ok) {
    ++counters_.commands_sent;
  } else {
    ++counters_.send_failures;
  }
  return result;
}

}  // namespace visvol::haptic
