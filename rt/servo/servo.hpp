// Servo: the haptic control law between the device and the rope.
//
// Contract with the rope (rt/rope) and the executive (rt/exec), per 1 kHz tick:
//   in:  time (s); the device sample (handle position, device mm; buttons;
//        fresh/valid); whether the device is operational; the grasped rope
//        point's world position (m) and velocity (m/s); grad F_p there (1/m,
//        world axes: x east, y north, z up).
//   out: the proxy's world position (m); the force to apply to the grasped
//        rope point (N, world); the device force command (N, device frame)
//        after safety; flags (grasping, clutched, forces enabled, awaiting a
//        new grasp, the safe-state reason).
//
// What it does:
//   - Workspace mapping: proxy_m = offset_m + scale * R * device_mm, with R the
//     device-to-world rotation. While the clutch button is held the proxy stays
//     put in the world and the hand moves freely; on release the offset is
//     re-indexed so that the proxy continues from where it stopped.
//   - Soft joint: while grasping, the proxy pulls the rope point through a
//     spring-damper: rope_force = K (proxy - point) + B (v_proxy - v_point).
//   - The hand feels the reaction scaled by hand_per_rope_force plus the
//     visibility cue cue_gain * grad F_p at the point (negative gain: the hand
//     is pushed toward lower visibility, i.e. toward hiding).
//   - Force safety, in this order: ramp-in over ramp_in_s after a grasp or a
//     clutch release; clamp of the magnitude to continuous_force_n; slew-rate
//     limit slew_n_per_s (a vector step limit, so the clamp still holds).
//     Any fault (device not operational, sample not valid, non-finite input, a
//     tick gap beyond max_tick_s or backwards, force_safe_state()) zeroes the
//     device force and the rope force in that same tick, ends the grasp and
//     withholds forces until the operator releases the grasp button and
//     presses it again. The same holds at start-up.
//
// Units: names carry them (_m, _mm, _n, _s, _per_m). Device frame of a Phantom:
// x right, y up, z toward the operator; the default R maps it to an operator
// facing north (device x -> east, y -> up, z -> south).
//
// Ownership: values in, values out; the servo holds only fixed-size state sized
// at construction. Thread-safety: step() from one thread (the real-time one);
// force_safe_state() from any thread (an atomic flag, acted on at the next
// step()). Cost: step() is a few hundred floating-point operations, O(1), no
// allocation, no locks, no system calls, no logging: real-time safe. create()
// validates and may allocate (the Status message): start-up only.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstdint>

#include "base/status.hpp"

namespace visvol::servo {

// Phantom device axes to world axes for an operator facing north.
Eigen::Matrix3d default_device_to_world();

struct ServoConfig {
  // Workspace mapping.
  double world_m_per_device_mm = 0.01;                          // scale: world metres per device millimetre
  Eigen::Vector3d world_offset_m = Eigen::Vector3d::Zero();     // world point at the device origin
  Eigen::Matrix3d device_to_world = default_device_to_world();  // rotation, det +1
  // Soft joint (world).
  double coupling_stiffness_n_per_m = 40.0;  // K
  double coupling_damping_n_s_per_m = 0.2;   // B
  double hand_per_rope_force = 1.0;          // hand force, N, per N of coupling force
  double cue_gain_n_m = 0.0;                 // cue force, N, per unit of grad F_p (1/m)
  // Safety.
  double continuous_force_n = 1.4;   // clamp: the device's continuous rating
  double slew_n_per_s = 100.0;       // largest change of the device force per second
  double ramp_in_s = 0.3;            // force ramps from 0 to full after (re)enable
  double velocity_cutoff_hz = 30.0;  // low-pass on the handle velocity estimate
  double max_tick_s = 0.02;          // a longer gap between ticks is a fault
  // Limits the configuration is checked against (the device's).
  double peak_force_n = 8.5;                    // continuous_force_n may not exceed it
  double max_device_stiffness_n_per_m = 800.0;  // stable at 1 kHz
  double max_device_damping_n_s_per_m = 5.0;
};

struct ServoInput {
  double time_s = 0.0;                                      // tick time, monotonic, s
  Eigen::Vector3d device_pos_mm = Eigen::Vector3d::Zero();  // handle, device frame, mm
  bool grasp_button = false;
  bool clutch_button = false;
  bool sample_fresh = false;                                    // a new device sample arrived this tick
  bool sample_valid = false;                                    // the driver holds a sample younger than its timeout
  bool device_operational = false;                              // the driver's state machine is operational
  bool point_valid = false;                                     // the rope gives a grasped (or graspable) point
  Eigen::Vector3d point_pos_m = Eigen::Vector3d::Zero();        // world, m
  Eigen::Vector3d point_vel_m_per_s = Eigen::Vector3d::Zero();  // world, m/s
  Eigen::Vector3d grad_fp_per_m = Eigen::Vector3d::Zero();      // grad F_p at the point, 1/m
};

// Why the force was zeroed this tick (none on a normal tick).
enum class SafeReason : std::uint8_t {
  none,
  invalid_input,    // a non-finite number in the input
  tick_gap,         // time went backwards or jumped by more than max_tick_s
  forced,           // force_safe_state() was called
  not_operational,  // the device driver is not operational
  stale_sample,     // no valid device sample
};
inline constexpr std::size_t kSafeReasons = 6;
const char* safe_reason_name(SafeReason reason);

struct ServoOutput {
  Eigen::Vector3d proxy_pos_m = Eigen::Vector3d::Zero();     // world, m
  Eigen::Vector3d rope_force_n = Eigen::Vector3d::Zero();    // on the grasped point, world, N
  Eigen::Vector3d device_force_n = Eigen::Vector3d::Zero();  // command, device frame, N
  bool device_enable = false;                                // send with enable on (false only with zero force)
  bool grasping = false;                                     // the soft joint holds a rope point
  bool clutched = false;                                     // the clutch button is held: proxy frozen, hand free
  bool forces_enabled = false;                               // grasping, unclutched: the hand feels the rope
  bool awaiting_regrasp = false;                             // forces withheld until the grasp button is pressed anew
  SafeReason safe_reason = SafeReason::none;
};

// Counters of safety events (read from the stepping thread).
struct ServoCounters {
  std::uint64_t ticks = 0;
  std::uint64_t safe_ticks[kSafeReasons] = {};  // ticks zeroed, per reason (index 0 unused)
  std::uint64_t clamped_ticks = 0;              // ticks whose force was clamped
  std::uint64_t slew_limited_ticks = 0;         // ticks whose force change was limited
  std::uint64_t grasps = 0;                     // grasps started
};

class Servo {
 public:
  // Checks every field (finite, in range, R a rotation, the stiffness and
  // damping the hand would feel within the device's stable limits) and names
  // the first bad one.
  static Status validate(const ServoConfig& config);
  static Result<Servo> create(const ServoConfig& config);

  Servo(Servo&& other) noexcept;
  Servo(const Servo&) = delete;
  Servo& operator=(const Servo&) = delete;
  Servo& operator=(Servo&&) = delete;

  // One tick. Real-time safe, O(1).
  ServoOutput step(const ServoInput& in);

  // Zeroes the force at the next step() and withholds it until the operator
  // grasps again (the executive calls this after overruns). Any thread.
  void force_safe_state() { safe_requested_.store(true, std::memory_order_release); }

  // Re-indexes the workspace as a clutch release does, so that the handle
  // where it is now puts the proxy at `proxy_m` (world, m): the executive
  // hands the operator the spooled rope's free end. The stepping thread.
  void reindex(const Eigen::Vector3d& proxy_m);
  // The configured mapping again (world_offset_m at the device origin).
  void restore_mapping();
  // Lets go of the grasp and withholds the rope and hand forces until the
  // operator releases the grasp button and presses it again (the executive
  // laid another rope under the hand). The stepping thread.
  void release_grasp();

  const ServoConfig& config() const { return config_; }
  // Where the proxy is now (world, m): the mapping applied to the last handle
  // position, or where the clutch froze it.
  Eigen::Vector3d proxy_m() const;
  const ServoCounters& counters() const { return counters_; }

 private:
  explicit Servo(const ServoConfig& config);

  SafeReason check(const ServoInput& in, double dt_s, bool forced) const;
  void track_device(const ServoInput& in);
  void track_buttons(const ServoInput& in, bool sample_usable, bool safe);
  Eigen::Vector3d shape_force(const Eigen::Vector3d& target_n, double dt_s);
  double ramp(double since_s, double now_s) const;

  // Per-tick state, apart from the constant configuration (a plain value, so
  // that the move constructor copies it whole).
  struct State {
    bool have_time = false;
    double last_time_s = 0.0;
    // Device motion, device frame.
    bool have_device = false;
    Eigen::Vector3d device_pos_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d device_vel_mm_per_s = Eigen::Vector3d::Zero();
    double last_sample_time_s = 0.0;
    // Mapping and buttons.
    Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d frozen_proxy_m = Eigen::Vector3d::Zero();
    bool clutched = false;
    bool grasp_was_down = true;  // unknown at start: treat as held, so a press is needed
    bool grasping = false;
    bool need_regrasp = true;
    double grasp_time_s = 0.0;  // ramp clock of the rope force
    double hand_time_s = 0.0;   // ramp clock of the hand force
    // Force shaping: the last device force command, device frame.
    Eigen::Vector3d device_force_n = Eigen::Vector3d::Zero();
  };

  ServoConfig config_;
  double alpha_per_s_;  // velocity filter bandwidth, rad/s
  State s_;
  std::atomic<bool> safe_requested_{false};
  ServoCounters counters_;
};

}  // namespace visvol::servo
