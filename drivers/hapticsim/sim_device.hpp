// SimDevice: a simulated 3-DOF haptic device (a Phantom Premium 1.5 stand-in)
// speaking the haptic protocol on any CanBus: a SocketCanBus in visvol-hapticsim,
// a MemoryBus endpoint in host tests.
//
// Model: a handle of mass mass_kg per axis with viscous and dry friction, end
// stops at the workspace edges, the operator's hand as a spring-damper pulling
// it toward a target, motor force = the last command saturated at peak_force_n
// (only in NMT operational, with enable set, no fault, and a command younger
// than command_timeout_ns: the device-side watchdog), encoder quantisation
// encoder_mm, and a first-order motor temperature that trips the
// over-temperature fault when forces stay high.
// Protocol: boot-up heartbeat at power-on, then pre-operational; NMT start ->
// operational: position every step (1 kHz), status every 10 ms, heartbeat
// every 50 ms; emergencies on faults and their reset.
// Fault injection: inject_*() below, from a script (script.hpp) or a test.
//
// Ownership: borrows the bus. Thread-safety: one thread. Cost: step() is
// O(pending frames + physics substeps); no allocation after construction.
#pragma once

#include <array>
#include <cstdint>
#include <random>

#include "base/status.hpp"
#include "drivers/can/can_bus.hpp"
#include "drivers/haptic/codec.hpp"
#include "drivers/haptic/protocol.hpp"

namespace visvol::hapticsim {

struct SimConfig {
  std::uint8_t node_id = haptic::kDefaultNodeId;
  double mass_kg = 0.075;                                          // apparent mass at the handle
  double viscous_n_s_per_m = 0.4;                                  // viscous friction
  double coulomb_n = 0.03;                                         // dry friction
  double peak_force_n = 8.5;                                       // motor force saturation
  double encoder_mm = 0.01;                                        // position quantisation
  std::array<double, 3> workspace_half_mm = {190.5, 133.5, 95.5};  // 381 x 267 x 191 mm
  double end_stop_n_per_m = 3000.0;                                // stiffness beyond the workspace
  double hand_stiffness_n_per_m = 300.0;                           // operator's grip
  double hand_damping_n_s_per_m = 3.0;
  std::int64_t command_timeout_ns = haptic::kDeviceCommandTimeoutNs;
  std::int64_t heartbeat_period_ns = haptic::kHeartbeatPeriodNs;
  std::int64_t status_period_ns = haptic::kStatusPeriodNs;
  std::int64_t boot_delay_ns = 0;  // powered off (silent) for this long first
  double ambient_c = 25.0;
  double heating_c_per_n2 = 10.0;  // steady-state rise per N^2 of force
  double thermal_time_s = 30.0;
  double over_temperature_c = 90.0;  // fault above, cleared 10 degC below
  double drop_fraction = 0.0;        // frames dropped in both directions
  std::uint64_t seed = 1;            // drops and garbage
};

// The operator's hand.
struct Hand {
  bool holding = true;                // false: the handle moves freely
  std::array<double, 3> target_mm{};  // where the hand pulls the handle
  bool grasp = false;                 // button 1
  bool clutch = false;                // button 2
  bool mode = false;                  // button 3: pull / spool mode
};

// What happened, for summaries and test assertions.
struct SimCounters {
  std::uint64_t frames_sent = 0;
  std::uint64_t send_failures = 0;
  std::uint64_t tx_dropped = 0;  // dropped by drop injection
  std::uint64_t rx_dropped = 0;
  std::uint64_t rx_ignored = 0;      // received while silent, bus-off or off
  std::uint64_t commands = 0;        // valid force commands received in operational
  std::uint64_t command_gaps = 0;    // commands missing between sequence numbers
  std::uint64_t malformed = 0;       // frames for this device that failed to decode
  std::uint64_t nmt_commands = 0;    // NMT commands for this node
  std::uint64_t watchdog_trips = 0;  // force zeroed for lack of commands
  std::uint64_t saturated_steps = 0;
  std::uint64_t force_steps = 0;  // steps with a non-zero motor force
  std::uint64_t operational_steps = 0;
  std::uint64_t boots = 0;
  std::uint64_t emergencies = 0;  // emergency frames sent (faults and resets)
  std::uint64_t garbage_sent = 0;
  std::uint64_t bus_off_events = 0;
  double max_force_n = 0.0;      // largest motor force applied
  double max_commanded_n = 0.0;  // largest enabled force command received
  double last_command_n = 0.0;   // the last force command received, and whether it enabled the motors
  bool last_command_enabled = false;
  std::int64_t first_operational_ns = -1;
};

class SimDevice {
 public:
  static Status validate(const SimConfig& config);
  static Result<SimDevice> create(const SimConfig& config, can::CanBus& bus, std::int64_t start_ns);

  // Advances to now_ns: receive, physics, send. Call about every 1 ms.
  void step(std::int64_t now_ns);

  void set_hand(const Hand& hand) { hand_ = hand; }
  const Hand& hand() const { return hand_; }

  // Fault injection (times in ns on the step() clock).
  void inject_drop(double fraction) {  // clamped to [0, 1]; NaN stops dropping
    config_.drop_fraction = fraction >= 0.0 ? (fraction <= 1.0 ? fraction : 1.0) : 0.0;
  }
  void inject_silence(std::int64_t now_ns, std::int64_t duration_ns);
  void inject_garbage(std::uint32_t frames) { garbage_left_ += frames; }
  void inject_wrong_length(std::int64_t now_ns, std::int64_t duration_ns);
  void inject_freeze(std::int64_t now_ns, std::int64_t duration_ns);
  void inject_reboot(std::int64_t now_ns, std::int64_t off_ns);
  void inject_bus_off(std::int64_t now_ns, std::int64_t duration_ns);
  void inject_emergency(std::int64_t now_ns, std::uint16_t fault_bit, std::int64_t duration_ns);

  bool powered() const { return powered_; }
  haptic::NmtState nmt_state() const { return nmt_; }
  std::array<double, 3> position_mm() const;
  const std::array<double, 3>& motor_force_n() const { return motor_force_n_; }
  std::uint16_t fault_bits() const { return fault_bits_; }
  double motor_temperature_c() const { return temperature_c_; }
  const SimCounters& counters() const { return counters_; }
  const SimConfig& config() const { return config_; }

 private:
  SimDevice(const SimConfig& config, can::CanBus& bus, std::int64_t start_ns);

  void power_on(std::int64_t now_ns);
  void receive(std::int64_t now_ns);
  void on_nmt(const haptic::NmtMsg& nmt, std::int64_t now_ns);
  void end_injections(std::int64_t now_ns);
  void update_motor(std::int64_t now_ns, double dt_s);
  void integrate(double dt_s);
  void transmit(std::int64_t now_ns);
  void send_heartbeat();
  void send_emergency(std::uint16_t code, std::uint8_t axis);
  void send_garbage();
  void send(can::CanFrame frame, bool own_frame);
  bool roll(double probability);

  SimConfig config_;
  can::CanBus* bus_;
  std::mt19937_64 rng_;
  can::CanFrame batch_[16];

  // Power and NMT.
  bool powered_ = false;
  std::int64_t power_on_at_ns_ = 0;
  haptic::NmtState nmt_ = haptic::NmtState::boot_up;
  std::int64_t next_heartbeat_ns_ = 0;
  std::int64_t next_status_ns_ = 0;
  std::int64_t last_step_ns_ = 0;
  std::uint8_t position_sequence_ = 0;
  std::uint8_t status_sequence_ = 0;

  // Commands and motors.
  haptic::CommandMsg command_;
  bool have_command_ = false;
  std::int64_t last_command_ns_ = 0;
  bool watchdog_tripped_ = false;
  bool saturated_ = false;
  std::array<double, 3> motor_force_n_{};
  double temperature_c_ = 25.0;
  std::uint16_t fault_bits_ = 0;
  std::uint16_t injected_fault_bit_ = 0;
  std::int64_t injected_fault_until_ns_ = 0;

  // Handle, device frame, m and m/s.
  std::array<double, 3> pos_m_{};
  std::array<double, 3> vel_m_per_s_{};
  Hand hand_;

  // Injections.
  std::int64_t silent_until_ns_ = 0;
  std::int64_t wrong_length_until_ns_ = 0;
  std::int64_t freeze_until_ns_ = 0;
  std::int64_t bus_off_until_ns_ = 0;
  bool bus_off_ = false;
  std::uint32_t garbage_left_ = 0;
  can::CanFrame last_position_frame_;
  can::CanFrame frozen_frame_;

  SimCounters counters_;
};

}  // namespace visvol::hapticsim
