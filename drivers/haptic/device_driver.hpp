// DeviceDriver: the console side of the haptic device protocol (protocol.md).
//
// Each 1 kHz tick the real-time thread calls, in order:
//   driver.poll(now_ns);                      // drain the bus, supervise, run NMT
//   ... servo.step(driver.sample(), driver.operational(), ...) ...
//   driver.command(force_n, enable);          // one force command frame
//
// States (derived every poll from what the device last said, in this priority):
//   fault(bus_off)         an error frame reported bus-off; until "restarted" or
//                          any frame arrives again
//   boot                   nothing heard from the device yet
//   fault(heartbeat_lost)  neither heartbeat nor status for 200 ms
//   fault(device_fault)    an emergency (error register != 0) or status fault
//                          bits; until an emergency reset, or clean status
//                          frames for 50 ms, or a reboot
//   pre_operational        the device is not operational: NMT start is sent now
//                          and every 100 ms
//   operational            device operational and a position within 10 ms
//   fault(position_timeout) was operational, no new position for 10 ms
// The driver recovers by itself: after a reboot (boot-up heartbeat) or bus-off
// it walks back through pre_operational to operational. Force is commanded only
// in `operational`; in every other state each command frame carries zero force
// with enable off (none at all in boot and bus-off).
//
// Positions are checked before use: a repeated sequence number (a frozen or
// replayed frame) is not a new sample, and a coordinate beyond the position
// limit or a jump faster than the speed limit is rejected and counted.
//
// Ownership: the driver borrows the bus (the caller keeps it alive).
// Thread-safety: one thread (the real-time one); read counters() there and
// publish copies. Cost: poll() is O(pending frames), at most
// max_frames_per_poll; command() is one send. Both are real-time safe: no
// allocation after create(), no locks, no logging, no blocking.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/status.hpp"
#include "drivers/can/can_bus.hpp"
#include "drivers/haptic/codec.hpp"
#include "drivers/haptic/protocol.hpp"

namespace visvol::haptic {

enum class DeviceState : std::uint8_t { boot, pre_operational, operational, fault };
enum class FaultReason : std::uint8_t {
  none,
  bus_off,
  heartbeat_lost,
  device_fault,
  position_timeout,
};
inline constexpr std::size_t kFaultReasons = 5;
const char* state_name(DeviceState state);
const char* fault_name(FaultReason reason);

struct DriverConfig {
  std::uint8_t node_id = kDefaultNodeId;                         // 1..127
  std::int64_t position_timeout_ns = kConsolePositionTimeoutNs;  // zero force after this silence
  std::int64_t heartbeat_timeout_ns = kHeartbeatTimeoutNs;       // device lost after this
  std::int64_t nmt_retry_ns = kNmtRetryNs;                       // NMT start repeat period
  std::int64_t fault_clear_ns = kFaultClearNs;                   // clean status needed after EMCY
  double position_limit_mm = 250.0;                              // |coordinate| beyond this is implausible
  double max_speed_mm_per_s = 5000.0;                            // faster jumps are implausible (a hand: < 3 m/s)
  double max_force_n = 8.5;                                      // command clamp, N (the device's peak force)
  std::size_t max_frames_per_poll = 256;                         // drain cap per tick (>> 21 frames/ms at 1 Mbit/s)
};

// The newest accepted position, as the servo reads it.
struct DeviceSample {
  std::array<double, 3> pos_mm{};  // handle position, device frame, mm
  std::uint8_t buttons = 0;        // kButtonGrasp | kButtonClutch
  std::int64_t timestamp_ns = 0;   // receive time of its frame
  bool fresh = false;              // accepted during the last poll()
  bool valid = false;              // the driver is operational (position younger than the timeout)
};

struct DriverCounters {
  std::uint64_t frames = 0;     // frames handed over by the bus
  std::uint64_t positions = 0;  // accepted position samples
  std::uint64_t statuses = 0;
  std::uint64_t heartbeats = 0;
  std::uint64_t emergencies = 0;    // emergency frames (faults and resets)
  std::uint64_t malformed = 0;      // wrong length, reserved bits, bad values
  std::uint64_t foreign = 0;        // valid frames of other nodes or console-bound kinds
  std::uint64_t duplicates = 0;     // position frames repeating the last sequence number
  std::uint64_t sequence_gaps = 0;  // position frames missing between sequence numbers
  std::uint64_t implausible = 0;    // positions out of range or jumping too fast
  std::uint64_t error_frames = 0;
  std::uint64_t bus_off = 0;
  std::uint64_t bus_restarts = 0;
  std::uint64_t device_reboots = 0;  // boot-up heartbeats after the first contact
  std::uint64_t nmt_sent = 0;
  std::uint64_t commands_sent = 0;
  std::uint64_t send_failures = 0;
  std::uint64_t rejected_commands = 0;                // non-finite forces replaced by zero
  std::uint64_t clamped_commands = 0;                 // forces clamped to max_force_n
  std::uint64_t capped_polls = 0;                     // polls that stopped at max_frames_per_poll
  std::array<std::uint64_t, kFaultReasons> faults{};  // entries into fault, per reason
};

// What the device last reported (for health messages).
struct DeviceReport {
  NmtState nmt_state = NmtState::boot_up;
  std::uint16_t fault_bits = 0;
  std::uint8_t status_flags = 0;
  double motor_temperature_c = 0.0;
  EmergencyMsg last_emergency;    // code 0 until the first emergency
  bool emergency_active = false;  // a latched emergency not yet cleared
};

class DeviceDriver {
 public:
  // Checks every field and names the first bad one.
  static Status validate(const DriverConfig& config);
  // The receive filters the device's frames need (heartbeat, status, position,
  // emergency), for the bus's configuration. Allocates: start-up only.
  static std::vector<can::CanFilter> receive_filters(std::uint8_t node_id);

  // Validates the configuration; the driver borrows `bus`. Start-up only.
  static Result<DeviceDriver> create(const DriverConfig& config, can::CanBus& bus);

  // Drains every pending frame, updates the state and sends NMT start when due.
  void poll(std::int64_t now_ns);

  // Sends one force command (device frame, N). Zero with enable off unless
  // operational; non-finite forces become zero, forces above max_force_n are
  // clamped along their direction. Errc::state when nothing may be sent (boot,
  // bus-off), else the bus's result.
  Errc command(const std::array<double, 3>& force_n, bool enable);

  DeviceState state() const { return state_; }
  FaultReason fault() const { return fault_; }
  bool operational() const { return state_ == DeviceState::operational; }
  const DeviceSample& sample() const { return sample_; }
  const DeviceReport& report() const { return report_; }
  const DriverCounters& counters() const { return counters_; }
  const CommandMsg& last_command() const { return last_command_; }
  const DriverConfig& config() const { return config_; }

 private:
  DeviceDriver(const DriverConfig& config, can::CanBus& bus) : config_(config), bus_(&bus) {}

  void on_frame(const can::CanFrame& frame);
  void on_heartbeat(const Message& m);
  void on_status(const Message& m);
  void on_emergency(const Message& m);
  void on_position(const Message& m);
  void update_state(std::int64_t now_ns);
  void send_nmt_start(std::int64_t now_ns);

  DriverConfig config_;
  can::CanBus* bus_;
  can::CanFrame batch_[16];

  DeviceState state_ = DeviceState::boot;
  FaultReason fault_ = FaultReason::none;
  bool seen_device_ = false;
  bool bus_off_ = false;
  std::int64_t last_alive_ns_ = 0;    // last heartbeat or status
  std::int64_t clean_since_ns_ = -1;  // first clean status after a fault report; -1: none
  std::int64_t last_nmt_ns_ = 0;
  bool nmt_due_ = true;  // send NMT start at the next chance
  bool have_sequence_ = false;
  std::uint8_t last_sequence_ = 0;
  bool have_position_ = false;
  std::uint8_t command_sequence_ = 0;

  DeviceSample sample_;
  DeviceReport report_;
  DriverCounters counters_;
  CommandMsg last_command_;
};

}  // namespace visvol::haptic
