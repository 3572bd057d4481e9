#include "drivers/haptic/can_device.hpp"

#include <utility>

namespace visvol::haptic {

rt::HapticState haptic_state(DeviceState s) {
  switch (s) {
    case DeviceState::boot: return rt::HapticState::boot;
    case DeviceState::pre_operational: return rt::HapticState::pre_operational;
    case DeviceState::operational: return rt::HapticState::operational;
    case DeviceState::fault: return rt::HapticState::fault;
  }
  return rt::HapticState::fault;
}

Result<CanDevice> CanDevice::create(const DriverConfig& config, can::CanBus& bus) {
  Result<DeviceDriver> driver = DeviceDriver::create(config, bus);
  if (!driver.ok()) return driver.status();
  return CanDevice(*driver, bus);
}

void CanDevice::poll(std::int64_t now_ns) {
  driver_.poll(now_ns);
  const DeviceSample& s = driver_.sample();
  sample_.position_mm = Eigen::Vector3d(s.pos_mm[0], s.pos_mm[1], s.pos_mm[2]);
  sample_.grasp_button = (s.buttons & kButtonGrasp) != 0;
  sample_.clutch_button = (s.buttons & kButtonClutch) != 0;
  sample_.mode_button = (s.buttons & kButtonMode) != 0;
  sample_.timestamp_ns = s.timestamp_ns;
  sample_.fresh = s.fresh;
  sample_.valid = s.valid;
}

rt::HapticHealth CanDevice::health() const {
  rt::HapticHealth h;
  h.state = state();
  h.fault_bits = driver_.report().fault_bits;
  h.motor_temperature_c = driver_.report().motor_temperature_c;
  const can::CanCounters& bus = bus_->counters();
  h.rx_frames = bus.received;
  h.tx_frames = bus.sent;
  h.errors = bus.error_frames + bus.send_failed + bus.dropped + bus.malformed;
  h.bus_off_count = bus.bus_off;
  return h;
}

Errc CanDevice::command(const Eigen::Vector3d& force_n, bool enable) {
  return driver_.command({force_n.x(), force_n.y(), force_n.z()}, enable);
}

}  // namespace visvol::haptic
