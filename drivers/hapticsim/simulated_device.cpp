#include "drivers/hapticsim/simulated_device.hpp"

#include <utility>

#include "drivers/haptic/device_driver.hpp"

namespace visvol::hapticsim {

SimulatedDevice::SimulatedDevice(Script script, std::int64_t start_ns)
    : bus_(2, 4096), script_(std::move(script)), start_ns_(start_ns) {}

Result<std::unique_ptr<SimulatedDevice>> SimulatedDevice::create(const SimConfig& config, Script script,
                                                                 std::int64_t start_ns) {
  std::unique_ptr<SimulatedDevice> s(new SimulatedDevice(std::move(script), start_ns));
  const std::uint8_t node = config.node_id;
  s->bus_.set_time_ns(start_ns);
  s->bus_.endpoint(0).set_filters(haptic::DeviceDriver::receive_filters(node), true);
  s->bus_.endpoint(1).set_filters(
      {{haptic::frame_id(haptic::MessageKind::command, node), 0x7FF}, {haptic::kNmtId, 0x7FF}}, false);
  Result<SimDevice> device = SimDevice::create(config, s->bus_.endpoint(1), start_ns);
  if (!device.ok()) return device.status().with_context("simulated device");
  s->device_.emplace(*device);
  s->player_.emplace(s->script_);
  return s;
}

void SimulatedDevice::step(std::int64_t now_ns) {
  bus_.set_time_ns(now_ns);
  player_->advance(static_cast<double>(now_ns - start_ns_) * 1e-9, now_ns, *device_);
  device_->step(now_ns);
}

}  // namespace visvol::hapticsim
