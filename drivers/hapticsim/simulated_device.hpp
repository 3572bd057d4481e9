// The simulated haptic device on an in-process CAN bus, stepped by the
// executive at stage 2 of each tick (rt::DeviceSimulation): the console's
// default device, and the rig of tests and benchmarks. The console's driver
// (haptic::CanDevice) talks to it through console_bus() exactly as it would
// to SocketCAN.
//
// Ownership: owns the bus, the device, the script and its player.
// Thread-safety: step() and console_bus() on the loop thread only (the bus is
// single-threaded); device() for reading there too. Cost: step() is O(frames),
// no allocation.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "drivers/can/memory_bus.hpp"
#include "drivers/hapticsim/script.hpp"
#include "drivers/hapticsim/sim_device.hpp"
#include "rt/exec/haptic_device.hpp"

namespace visvol::hapticsim {

class SimulatedDevice final : public rt::DeviceSimulation {
 public:
  // `script` may be empty (the hand rests at the centre); start_ns is when the
  // script's time 0 falls (CLOCK_MONOTONIC, or any clock the ticks use).
  static Result<std::unique_ptr<SimulatedDevice>> create(const SimConfig& config, Script script, std::int64_t start_ns);

  void step(std::int64_t now_ns) override;
  can::CanBus& console_bus() { return bus_.endpoint(0); }
  const SimDevice& device() const { return *device_; }
  bool script_ended() const { return player_->ended(); }

 private:
  SimulatedDevice(Script script, std::int64_t start_ns);
  can::MemoryBus bus_;
  Script script_;
  std::optional<SimDevice> device_;
  std::optional<Player> player_;
  std::int64_t start_ns_;
};

}  // namespace visvol::hapticsim
