// A console for tests: the device driver, the servo and a stand-in rope wired
// as the application will wire them, one 1 kHz tick at a time. Used by the host
// safety tests (in-process bus, simulated time) and the vcan suite (real
// sockets, real time). Also the checks both run on the recorded bus traffic.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "drivers/haptic/codec.hpp"
#include "drivers/haptic/device_driver.hpp"
#include "rt/servo/servo.hpp"

namespace visvol::testing {

// A rope point held by a spring to its anchor: what the operator pulls.
struct StandInRope {
  Eigen::Vector3d anchor_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d pos_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d vel_m_per_s = Eigen::Vector3d::Zero();
  double stiffness_n_per_m = 100.0;
  double damping_n_s_per_m = 20.0;
  double mass_kg = 1.0;
  Eigen::Vector3d grad_fp_per_m = Eigen::Vector3d(0.05, 0.0, 0.2);  // more visible up and east

  void step(const Eigen::Vector3d& force_n, double dt_s) {
    const Eigen::Vector3d f = force_n - stiffness_n_per_m * (pos_m - anchor_m) - damping_n_s_per_m * vel_m_per_s;
    vel_m_per_s += f / mass_kg * dt_s;
    pos_m += vel_m_per_s * dt_s;
  }
};

// What one tick did.
struct ConsoleTick {
  std::int64_t t_ns = 0;
  haptic::DeviceState state = haptic::DeviceState::boot;
  haptic::FaultReason fault = haptic::FaultReason::none;
  bool sample_valid = false;
  bool grasp_button = false;
  servo::ServoOutput out;
  Errc sent = Errc::ok;  // the driver's command() result
};

inline servo::ServoConfig test_servo_config() {
  servo::ServoConfig c;   // 0.01 m/mm, K 40 N/m (400 N/m in the hand), 1.4 N, 100 N/s, 0.3 s
  c.cue_gain_n_m = -0.5;  // hide: pushed down the visibility gradient
  return c;
}

class Console {
 public:
  Console(haptic::DeviceDriver driver, servo::Servo servo) : driver_(std::move(driver)), servo_(std::move(servo)) {}

  // One tick at now_ns: poll, servo, rope, command. Real-time safe (no allocation).
  ConsoleTick tick(std::int64_t now_ns) {
    driver_.poll(now_ns);
    const haptic::DeviceSample& sample = driver_.sample();
    servo::ServoInput in;
    in.time_s = static_cast<double>(now_ns) * 1e-9;
    in.device_pos_mm = Eigen::Vector3d(sample.pos_mm[0], sample.pos_mm[1], sample.pos_mm[2]);
    in.grasp_button = (sample.buttons & haptic::kButtonGrasp) != 0;
    in.clutch_button = (sample.buttons & haptic::kButtonClutch) != 0;
    in.sample_fresh = sample.fresh;
    in.sample_valid = sample.valid;
    in.device_operational = driver_.operational();
    in.point_valid = true;
    in.point_pos_m = rope_.pos_m;
    in.point_vel_m_per_s = rope_.vel_m_per_s;
    in.grad_fp_per_m = rope_.grad_fp_per_m;
    ConsoleTick t;
    t.t_ns = now_ns;
    t.out = servo_.step(in);
    const double dt_s = last_ns_ == 0 ? 1e-3 : std::min(static_cast<double>(now_ns - last_ns_) * 1e-9, 0.02);
    last_ns_ = now_ns;
    rope_.step(t.out.rope_force_n, dt_s);
    const Eigen::Vector3d& f = t.out.device_force_n;
    t.sent = driver_.command({f.x(), f.y(), f.z()}, t.out.device_enable);
    t.state = driver_.state();
    t.fault = driver_.fault();
    t.sample_valid = sample.valid;
    t.grasp_button = in.grasp_button;
    return t;
  }

  haptic::DeviceDriver& driver() { return driver_; }
  servo::Servo& servo() { return servo_; }
  StandInRope& rope() { return rope_; }

 private:
  haptic::DeviceDriver driver_;
  servo::Servo servo_;
  StandInRope rope_;
  std::int64_t last_ns_ = 0;
};

// One frame seen on the bus (candump's view).
struct BusFrame {
  std::int64_t t_ns = 0;
  can::CanFrame frame;
};

struct TrafficLimits {
  std::uint8_t node = 1;
  double max_force_n = 1.4;  // the servo's clamp
  double slew_n_per_s = 100.0;
  std::int64_t position_timeout_ns = 10'000'000;
  std::int64_t slack_ns = 0;  // timing tolerance (0 in simulated time)
};

using haptic::norm3;

// Protocol invariants of the console's traffic, from the bus alone:
//  - every console frame is a valid NMT or force command for this node;
//  - forces never exceed the clamp; enable off carries zero force;
//  - a non-zero force is sent only within the position timeout of the last new
//    position frame (a valid frame with a sequence number not seen just before);
//  - a non-zero force changes by at most slew x (elapsed time + slack), plus
//    2 mN of rounding, from the previous command.
// Returns the number of non-zero force commands.
inline int check_console_traffic(const std::vector<BusFrame>& frames, const TrafficLimits& lim) {
  int nonzero = 0;
  std::int64_t last_position_ns = -1;
  int last_sequence = -1;
  bool have_prev = false;
  std::array<double, 3> prev{};
  std::int64_t prev_ns = 0;
  for (const BusFrame& bf : frames) {
    if (bf.frame.is_error()) continue;
    haptic::Message m;
    const haptic::DecodeError e = haptic::decode(bf.frame, m);
    const std::uint32_t id = bf.frame.id;
    if (id == haptic::frame_id(haptic::MessageKind::position, lim.node) && e == haptic::DecodeError::ok) {
      if (m.position.sequence != last_sequence) last_position_ns = bf.t_ns;
      last_sequence = m.position.sequence;
      continue;
    }
    const bool from_console = id == haptic::kNmtId || id == haptic::frame_id(haptic::MessageKind::command, lim.node);
    if (!from_console) continue;
    EXPECT_EQ(e, haptic::DecodeError::ok) << "console frame id " << id << " at " << bf.t_ns;
    if (e != haptic::DecodeError::ok || m.kind != haptic::MessageKind::command) continue;
    const std::array<double, 3>& f = m.command.force_n;
    const double magnitude = norm3(f);
    EXPECT_LE(magnitude, lim.max_force_n + 1e-9) << "at " << bf.t_ns;
    if (!m.command.enable) {
      EXPECT_EQ(magnitude, 0.0) << "enable off with force at " << bf.t_ns;
    }
    if (magnitude > 0.0) {
      ++nonzero;
      EXPECT_GE(last_position_ns, 0) << "force before any position, at " << bf.t_ns;
      EXPECT_LT(bf.t_ns - last_position_ns, lim.position_timeout_ns + lim.slack_ns)
          << "force " << static_cast<double>(bf.t_ns - last_position_ns) / 1e6 << " ms after the last position";
      if (have_prev) {
        const std::array<double, 3> d = {f[0] - prev[0], f[1] - prev[1], f[2] - prev[2]};
        const double dt_s = static_cast<double>(bf.t_ns - prev_ns + lim.slack_ns) * 1e-9;
        EXPECT_LE(norm3(d), lim.slew_n_per_s * std::max(dt_s, 1e-3) + 2e-3) << "jump at " << bf.t_ns;
      }
    }
    have_prev = true;
    prev = f;
    prev_ns = bf.t_ns;
  }
  return nonzero;
}

// The console's own record: zero force in every tick outside operational or in
// a safe state, and force only after a release of the grasp button that
// followed the last fault (or start-up): "forces come back only after the
// operator grasps again".
inline void check_console_ticks(const std::vector<ConsoleTick>& ticks) {
  bool blocked = true;  // until the button is seen released
  for (const ConsoleTick& t : ticks) {
    const bool safe = t.out.safe_reason != servo::SafeReason::none;
    if (safe || t.state != haptic::DeviceState::operational) {
      EXPECT_TRUE(t.out.device_force_n.isZero(0.0)) << "force outside operational at " << t.t_ns;
      blocked = true;
    }
    if (t.sample_valid && !t.grasp_button) blocked = false;
    if (t.out.forces_enabled) {
      EXPECT_FALSE(blocked) << "forces without a new grasp at " << t.t_ns;
    }
  }
}

}  // namespace visvol::testing
