// The haptic device as the executive's tick sees it: poll, the latest sample,
// a force command, and its health for the device-status message. The CAN
// driver (drivers/haptic/can_device.hpp) implements it over any CAN bus;
// app/ wires one in. The executive knows no bus, protocol or simulator.
//
// Thread-safety: the loop thread only. Real-time safe: no allocation, lock or
// blocking call in any of these, error paths included.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "base/status.hpp"

namespace visvol::rt {

enum class HapticState : std::uint8_t { boot, pre_operational, operational, fault };

inline const char* to_string(HapticState s) {
  switch (s) {
    case HapticState::boot: return "boot";
    case HapticState::pre_operational: return "pre-operational";
    case HapticState::operational: return "operational";
    case HapticState::fault: return "fault";
  }
  return "unknown";
}

// The newest accepted handle position, as the servo reads it.
struct HapticSample {
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  // device frame, mm
  bool grasp_button = false;
  bool clutch_button = false;
  bool mode_button = false;       // each press switches between pull (mode A) and spool (mode B)
  std::int64_t timestamp_ns = 0;  // when it arrived; 0: none yet
  bool fresh = false;             // accepted during the last poll()
  bool valid = false;             // the device is operational and the position recent
};

// What the device-status message reports.
struct HapticHealth {
  HapticState state = HapticState::boot;
  std::uint16_t fault_bits = 0;
  double motor_temperature_c = 0.0;
  std::uint64_t rx_frames = 0;
  std::uint64_t tx_frames = 0;
  std::uint64_t errors = 0;  // error frames, refused sends, drops, malformed reads
  std::uint64_t bus_off_count = 0;
};

class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  // Takes what arrived since the last poll and advances the device's state.
  virtual void poll(std::int64_t now_ns) = 0;
  virtual const HapticSample& sample() const = 0;
  virtual HapticState state() const = 0;
  virtual HapticHealth health() const = 0;
  // One force command, device frame, N (zero and off where the device may not
  // take it). Errc::state when nothing may be sent yet; another code when the
  // bus refused it.
  virtual Errc command(const Eigen::Vector3d& force_n, bool enable) = 0;
};

// Runs at stage 2 of each tick on the loop thread, before the device is
// polled: a simulated device on an in-process bus (real-time safe).
class DeviceSimulation {
 public:
  virtual ~DeviceSimulation() = default;
  virtual void step(std::int64_t now_ns) = 0;
};

}  // namespace visvol::rt
