// The haptic device over CAN: the executive's HapticDevice (rt/exec/
// haptic_device.hpp) implemented by the protocol's DeviceDriver on any CAN
// bus (SocketCAN, or the in-process bus of the simulated device).
//
// Ownership: owns its driver; borrows the bus (the caller keeps it alive
// longer). Thread-safety and cost: as DeviceDriver (the loop thread;
// real-time safe after create()).
#pragma once

#include "drivers/can/can_bus.hpp"
#include "drivers/haptic/device_driver.hpp"
#include "rt/exec/haptic_device.hpp"

namespace visvol::haptic {

rt::HapticState haptic_state(DeviceState s);

class CanDevice final : public rt::HapticDevice {
 public:
  // Validates the configuration (names the first bad field). Start-up only.
  static Result<CanDevice> create(const DriverConfig& config, can::CanBus& bus);
  // Movable, not copyable: a copy would be a second driver on the same bus.
  CanDevice(CanDevice&&) = default;
  CanDevice& operator=(CanDevice&&) = default;

  void poll(std::int64_t now_ns) override;
  const rt::HapticSample& sample() const override { return sample_; }
  rt::HapticState state() const override { return haptic_state(driver_.state()); }
  rt::HapticHealth health() const override;
  Errc command(const Eigen::Vector3d& force_n, bool enable) override;

  const DeviceDriver& driver() const { return driver_; }

 private:
  CanDevice(const DeviceDriver& driver, can::CanBus& bus) : driver_(driver), bus_(&bus) {}

  DeviceDriver driver_;
  can::CanBus* bus_;
  rt::HapticSample sample_;
};

}  // namespace visvol::haptic
