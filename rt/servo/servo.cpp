#include "rt/servo/servo.hpp"

#include <Eigen/LU>
#include <cmath>
#include <string>

#include "base/angles.hpp"

namespace visvol::servo {
namespace {

constexpr double kMmPerM = 1000.0;

bool finite(double v) { return std::isfinite(v); }

Status bad(const std::string& field, const std::string& why) {
  return invalid_argument("servo configuration: " + field + " " + why);
}

// A finite value in [lo, hi].
Status check_range(const char* field, double v, double lo, double hi, const char* unit) {
  if (!finite(v) || v < lo || v > hi) {
    return bad(field, "= " + std::to_string(v) + " " + unit + " is outside [" + std::to_string(lo) + ", " +
                          std::to_string(hi) + "]");
  }
  return Status::ok_status();
}

}  // namespace

Eigen::Matrix3d default_device_to_world() {
  Eigen::Matrix3d r;
  // Columns: where device x (right), y (up), z (toward the operator) point in
  // the world of an operator facing north.
  r.col(0) = Eigen::Vector3d(1.0, 0.0, 0.0);   // east
  r.col(1) = Eigen::Vector3d(0.0, 0.0, 1.0);   // up
  r.col(2) = Eigen::Vector3d(0.0, -1.0, 0.0);  // south
  return r;
}

const char* safe_reason_name(SafeReason reason) {
  switch (reason) {
    case SafeReason::none: return "none";
    case SafeReason::invalid_input: return "invalid input";
    case SafeReason::tick_gap: return "tick gap";
    case SafeReason::forced: return "forced safe state";
    case SafeReason::not_operational: return "device not operational";
    case SafeReason::stale_sample: return "stale device sample";
  }
  return "invalid";
}

Status Servo::validate(const ServoConfig& c) {
  constexpr double kHuge = 1e9;
  VISVOL_RETURN_IF_ERROR(check_range("world_m_per_device_mm", c.world_m_per_device_mm, 1e-9, 1e6, "m/mm"));
  if (!c.world_offset_m.allFinite()) return bad("world_offset_m", "is not finite");
  const Eigen::Matrix3d& r = c.device_to_world;
  if (!r.allFinite() || (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-6 || r.determinant() < 0.0) {
    return bad("device_to_world", "is not a rotation (orthonormal, determinant +1)");
  }
  VISVOL_RETURN_IF_ERROR(check_range("coupling_stiffness_n_per_m", c.coupling_stiffness_n_per_m, 0.0, kHuge, "N/m"));
  VISVOL_RETURN_IF_ERROR(check_range("coupling_damping_n_s_per_m", c.coupling_damping_n_s_per_m, 0.0, kHuge, "N s/m"));
  VISVOL_RETURN_IF_ERROR(check_range("hand_per_rope_force", c.hand_per_rope_force, 0.0, kHuge, ""));
  VISVOL_RETURN_IF_ERROR(check_range("cue_gain_n_m", c.cue_gain_n_m, -kHuge, kHuge, "N m"));
  VISVOL_RETURN_IF_ERROR(check_range("peak_force_n", c.peak_force_n, 0.0, 32.0, "N"));
  VISVOL_RETURN_IF_ERROR(check_range("continuous_force_n", c.continuous_force_n, 1e-3, c.peak_force_n, "N"));
  VISVOL_RETURN_IF_ERROR(check_range("slew_n_per_s", c.slew_n_per_s, 1e-3, kHuge, "N/s"));
  VISVOL_RETURN_IF_ERROR(check_range("ramp_in_s", c.ramp_in_s, 0.0, 60.0, "s"));
  VISVOL_RETURN_IF_ERROR(check_range("velocity_cutoff_hz", c.velocity_cutoff_hz, 0.1, 500.0, "Hz"));
  VISVOL_RETURN_IF_ERROR(check_range("max_tick_s", c.max_tick_s, 1e-4, 1.0, "s"));
  VISVOL_RETURN_IF_ERROR(
      check_range("max_device_stiffness_n_per_m", c.max_device_stiffness_n_per_m, 0.0, kHuge, "N/m"));
  VISVOL_RETURN_IF_ERROR(
      check_range("max_device_damping_n_s_per_m", c.max_device_damping_n_s_per_m, 0.0, kHuge, "N s/m"));
  // What the hand feels per metre of handle motion: hand gain x K x (world m per handle m).
  const double handle_scale = c.world_m_per_device_mm * kMmPerM;
  const double felt_stiffness = c.hand_per_rope_force * c.coupling_stiffness_n_per_m * handle_scale;
  if (felt_stiffness > c.max_device_stiffness_n_per_m) {
    return bad("coupling_stiffness_n_per_m", "makes the hand feel " + std::to_string(felt_stiffness) +
                                                 " N/m, above the device's stable " +
                                                 std::to_string(c.max_device_stiffness_n_per_m) +
                                                 " N/m (hand_per_rope_force x K x world_m_per_device_mm x 1000)");
  }
  const double felt_damping = c.hand_per_rope_force * c.coupling_damping_n_s_per_m * handle_scale;
  if (felt_damping > c.max_device_damping_n_s_per_m) {
    return bad("coupling_damping_n_s_per_m", "makes the hand feel " + std::to_string(felt_damping) +
                                                 " N s/m, above the device's " +
                                                 std::to_string(c.max_device_damping_n_s_per_m) + " N s/m");
  }
  return Status::ok_status();
}

Result<Servo> Servo::create(const ServoConfig& config) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  return Servo(config);
}

Servo::Servo(const ServoConfig& config) : config_(config), alpha_per_s_(2.0 * kPi * config.velocity_cutoff_hz) {
  s_.offset_m = config.world_offset_m;
}

Servo::Servo(Servo&& other) noexcept
    : config_(other.config_),
      alpha_per_s_(other.alpha_per_s_),
      s_(other.s_),
      safe_requested_(other.safe_requested_.load(std::memory_order_acquire)),
      counters_(other.counters_) {}

ServoOutput Servo::step(const ServoInput& in) {
  ++counters_.ticks;
  const bool forced = safe_requested_.exchange(false, std::memory_order_acq_rel);
  const double dt_s = s_.have_time ? in.time_s - s_.last_time_s : 0.0;
  const SafeReason reason = check(in, dt_s, forced);
  const bool safe = reason != SafeReason::none;
  if (finite(in.time_s)) {
    s_.have_time = true;
    s_.last_time_s = in.time_s;
  }

  // Mapping and buttons follow every usable sample, even in a safe state.
  const bool sample_usable = in.sample_valid && in.device_pos_mm.allFinite();
  if (sample_usable) track_device(in);
  track_buttons(in, sample_usable, safe);

  ServoOutput out;
  out.proxy_pos_m = proxy_m();
  if (safe) {
    // Zero now, in this tick: no slew on the way down from a fault.
    s_.device_force_n.setZero();
    ++counters_.safe_ticks[static_cast<std::size_t>(reason)];
    out.safe_reason = reason;
  } else {
    // Soft joint and cue.
    Eigen::Vector3d hand_world_n = Eigen::Vector3d::Zero();
    if (s_.grasping && in.point_valid) {
      const Eigen::Vector3d proxy_vel_m_per_s =
          s_.clutched
              ? Eigen::Vector3d::Zero()
              : Eigen::Vector3d(config_.world_m_per_device_mm * (config_.device_to_world * s_.device_vel_mm_per_s));
      const Eigen::Vector3d coupling_n =
          config_.coupling_stiffness_n_per_m * (out.proxy_pos_m - in.point_pos_m) +
          config_.coupling_damping_n_s_per_m * (proxy_vel_m_per_s - in.point_vel_m_per_s);
      out.rope_force_n = ramp(s_.grasp_time_s, in.time_s) * coupling_n;
      if (!s_.clutched) {
        hand_world_n = ramp(s_.hand_time_s, in.time_s) *
                       (-config_.hand_per_rope_force * coupling_n + config_.cue_gain_n_m * in.grad_fp_per_m);
      }
    }
    // Safety shaping in the device frame.
    out.device_force_n = shape_force(config_.device_to_world.transpose() * hand_world_n, dt_s);
  }
  out.grasping = s_.grasping;
  out.clutched = s_.clutched;
  out.forces_enabled = s_.grasping && !s_.clutched && !safe;
  out.awaiting_regrasp = s_.need_regrasp;
  out.device_enable = out.forces_enabled || !out.device_force_n.isZero(0.0);
  return out;
}

SafeReason Servo::check(const ServoInput& in, double dt_s, bool forced) const {
  const bool inputs_finite = finite(in.time_s) && (!in.sample_valid || in.device_pos_mm.allFinite()) &&
                             (!in.point_valid || (in.point_pos_m.allFinite() && in.point_vel_m_per_s.allFinite() &&
                                                  in.grad_fp_per_m.allFinite()));
  if (!inputs_finite) return SafeReason::invalid_input;
  if (s_.have_time && (!(dt_s > 0.0) || dt_s > config_.max_tick_s)) return SafeReason::tick_gap;
  if (forced) return SafeReason::forced;
  if (!in.device_operational) return SafeReason::not_operational;
  if (!in.sample_valid) return SafeReason::stale_sample;
  return SafeReason::none;
}

void Servo::track_device(const ServoInput& in) {
  if (s_.have_device && !in.sample_fresh) return;  // same sample as before: hold
  if (s_.have_device) {
    const double gap_s = in.time_s - s_.last_sample_time_s;
    if (gap_s > 0.0 && gap_s <= config_.max_tick_s) {
      // First-order low-pass of the finite difference (exact for a constant input).
      const Eigen::Vector3d raw_mm_per_s = (in.device_pos_mm - s_.device_pos_mm) / gap_s;
      const double a = 1.0 - std::exp(-alpha_per_s_ * gap_s);
      s_.device_vel_mm_per_s += a * (raw_mm_per_s - s_.device_vel_mm_per_s);
    } else {
      s_.device_vel_mm_per_s.setZero();  // no derivative across a gap
    }
  }
  s_.device_pos_mm = in.device_pos_mm;
  s_.last_sample_time_s = in.time_s;
  s_.have_device = true;
}

void Servo::track_buttons(const ServoInput& in, bool sample_usable, bool safe) {
  if (safe) {
    s_.grasping = false;
    s_.need_regrasp = true;
  }
  if (!sample_usable) return;  // buttons unknown
  // Clutch: freeze the proxy, re-index the offset on release.
  if (in.clutch_button && !s_.clutched) {
    s_.frozen_proxy_m = proxy_m();
    s_.clutched = true;
  } else if (!in.clutch_button && s_.clutched) {
    s_.offset_m = s_.frozen_proxy_m - config_.world_m_per_device_mm * (config_.device_to_world * s_.device_pos_mm);
    s_.clutched = false;
    s_.hand_time_s = in.time_s;  // the hand force ramps in again
  }
  // Grasp: a press after a release, outside any safe state.
  if (!in.grasp_button) {
    s_.grasping = false;
    s_.need_regrasp = false;
  } else if (!s_.grasp_was_down && !s_.need_regrasp && !safe && !s_.grasping) {
    s_.grasping = true;
    s_.grasp_time_s = in.time_s;
    s_.hand_time_s = in.time_s;
    ++counters_.grasps;
  }
  s_.grasp_was_down = in.grasp_button;
}

void Servo::reindex(const Eigen::Vector3d& proxy_m) {
  if (!proxy_m.allFinite()) return;
  s_.offset_m = proxy_m - config_.world_m_per_device_mm * (config_.device_to_world * s_.device_pos_mm);
  s_.frozen_proxy_m = proxy_m;
}

void Servo::restore_mapping() {
  s_.offset_m = config_.world_offset_m;
  s_.frozen_proxy_m = s_.offset_m + config_.world_m_per_device_mm * (config_.device_to_world * s_.device_pos_mm);
}

void Servo::release_grasp() {
  s_.grasping = false;
  s_.need_regrasp = true;
}

Eigen::Vector3d Servo::proxy_m() const {
  if (s_.clutched) return s_.frozen_proxy_m;
  return s_.offset_m + config_.world_m_per_device_mm * (config_.device_to_world * s_.device_pos_mm);
}

double Servo::ramp(double since_s, double now_s) const {
  if (config_.ramp_in_s <= 0.0) return 1.0;
  const double r = (now_s - since_s) / config_.ramp_in_s;
  return r <= 0.0 ? 0.0 : (r >= 1.0 ? 1.0 : r);
}

Eigen::Vector3d Servo::shape_force(const Eigen::Vector3d& target_n, double dt_s) {
  const double limit_n = config_.continuous_force_n;
  // Clamp the magnitude, keeping the direction.
  Eigen::Vector3d goal_n = target_n;
  const double goal_norm_n = goal_n.norm();
  if (goal_norm_n > limit_n) {
    goal_n *= limit_n / goal_norm_n;
    ++counters_.clamped_ticks;
  }
  // Slew: a step of at most slew x dt toward the goal. Both ends lie in the
  // clamp ball, so the result does too (up to rounding, removed below).
  const double max_step_n = config_.slew_n_per_s * (dt_s > 0.0 ? dt_s : 0.0);
  Eigen::Vector3d step_n = goal_n - s_.device_force_n;
  const double step_norm_n = step_n.norm();
  if (step_norm_n > max_step_n) {
    step_n *= max_step_n / step_norm_n;
    ++counters_.slew_limited_ticks;
  }
  s_.device_force_n += step_n;
  const double out_norm_n = s_.device_force_n.norm();
  if (out_norm_n > limit_n) s_.device_force_n *= limit_n / out_norm_n;
  return s_.device_force_n;
}

}  // namespace visvol::servo
