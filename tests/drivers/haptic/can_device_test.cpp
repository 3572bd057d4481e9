// haptic::CanDevice: the executive's view of the haptic device (rt::HapticDevice)
// over the CAN driver, against the simulated device on the in-process bus.
#include "drivers/haptic/can_device.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "drivers/hapticsim/simulated_device.hpp"

namespace visvol::haptic {
namespace {

constexpr std::int64_t kMs = 1000000;

class CanDeviceTest : public ::testing::Test {
 protected:
  void start(const char* script) {
    hapticsim::SimConfig sc;
    auto s = hapticsim::parse_script(script, "test script", sc.workspace_half_mm);
    ASSERT_TRUE(s.ok()) << s.status().message();
    auto sim = hapticsim::SimulatedDevice::create(sc, *s, now_ns_);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    sim_ = std::move(*sim);
    auto device = CanDevice::create(DriverConfig{}, sim_->console_bus());
    ASSERT_TRUE(device.ok()) << device.status().message();
    device_ = std::make_unique<CanDevice>(std::move(*device));
  }
  // Ticks of 1 ms as the executive runs them: the simulation, the poll, a command.
  void run(int ticks, const Eigen::Vector3d& force_n = Eigen::Vector3d::Zero(), bool enable = false) {
    for (int k = 0; k < ticks; ++k) {
      now_ns_ += kMs;
      sim_->step(now_ns_);
      device_->poll(now_ns_);
      last_sent_ = device_->command(force_n, enable);
    }
  }

  std::int64_t now_ns_ = 1000 * kMs;
  std::unique_ptr<hapticsim::SimulatedDevice> sim_;
  std::unique_ptr<CanDevice> device_;  // after sim_: destroyed first
  Errc last_sent_ = Errc::ok;
};

TEST(HapticState, MapsEveryDriverState) {
  EXPECT_EQ(haptic_state(DeviceState::boot), rt::HapticState::boot);
  EXPECT_EQ(haptic_state(DeviceState::pre_operational), rt::HapticState::pre_operational);
  EXPECT_EQ(haptic_state(DeviceState::operational), rt::HapticState::operational);
  EXPECT_EQ(haptic_state(DeviceState::fault), rt::HapticState::fault);
  EXPECT_STREQ(rt::to_string(rt::HapticState::pre_operational), "pre-operational");
}

TEST_F(CanDeviceTest, RefusesABadConfigurationNamingTheField) {
  hapticsim::SimConfig sc;
  auto sim = hapticsim::SimulatedDevice::create(sc, {}, now_ns_);
  ASSERT_TRUE(sim.ok());
  DriverConfig bad;
  bad.node_id = 0;
  const auto device = CanDevice::create(bad, (*sim)->console_bus());
  ASSERT_FALSE(device.ok());
  EXPECT_NE(device.status().message().find("node"), std::string::npos) << device.status().message();
}

// Before the device speaks nothing may be sent; once it is operational the
// executive reads the hand's position and buttons, and the health counts the
// bus's frames.
TEST_F(CanDeviceTest, ComesUpAndReportsTheHandAndTheBus) {
  ASSERT_NO_FATAL_FAILURE(start("0.05 move 10 -20 5 0.1\n0.2 grab\n"));
  EXPECT_EQ(device_->state(), rt::HapticState::boot);
  EXPECT_FALSE(device_->sample().valid);
  // the executive counts every refusal but this one as a send failure
  EXPECT_EQ(device_->command(Eigen::Vector3d(1, 0, 0), true), Errc::state);
  run(400);
  EXPECT_EQ(device_->state(), rt::HapticState::operational);
  const rt::HapticSample& s = device_->sample();
  EXPECT_TRUE(s.valid);
  EXPECT_GT(s.timestamp_ns, now_ns_ - 5 * kMs);
  EXPECT_NEAR(s.position_mm.x(), 10.0, 1.0);
  EXPECT_NEAR(s.position_mm.y(), -20.0, 1.0);
  EXPECT_NEAR(s.position_mm.z(), 5.0, 1.0);
  EXPECT_TRUE(s.grasp_button);
  EXPECT_FALSE(s.clutch_button);
  EXPECT_EQ(last_sent_, Errc::ok);
  const rt::HapticHealth h = device_->health();
  EXPECT_EQ(h.state, rt::HapticState::operational);
  EXPECT_GT(h.rx_frames, 300u);  // a position a millisecond
  EXPECT_GT(h.tx_frames, 300u);  // a command a tick
  EXPECT_EQ(h.errors, 0u);
  EXPECT_EQ(h.fault_bits, 0u);
}

// The force reaches the motors only while enabled, and the device's own faults
// show in the state and the health, and zero what is sent.
TEST_F(CanDeviceTest, CommandsTheForceAndReportsAFault) {
  ASSERT_NO_FATAL_FAILURE(start("0.3 emergency over-current 0.2\n"));
  run(200, Eigen::Vector3d(0.5, 0.0, -0.25), false);
  ASSERT_EQ(device_->state(), rt::HapticState::operational);
  EXPECT_FALSE(device_->driver().last_command().enable);
  EXPECT_EQ(sim_->device().motor_force_n()[0], 0.0);  // not enabled: no force
  run(50, Eigen::Vector3d(0.5, 0.0, -0.25), true);
  ASSERT_EQ(device_->state(), rt::HapticState::operational);
  EXPECT_NEAR(sim_->device().motor_force_n()[0], 0.5, 0.01);
  EXPECT_NEAR(sim_->device().motor_force_n()[2], -0.25, 0.01);
  run(100, Eigen::Vector3d(0.5, 0.0, -0.25), true);  // into the emergency
  EXPECT_EQ(device_->state(), rt::HapticState::fault);
  EXPECT_NE(device_->health().fault_bits, 0u);
  // the driver itself withholds the force, whatever the simulator does
  EXPECT_FALSE(device_->driver().last_command().enable);
  EXPECT_EQ(device_->driver().last_command().force_n[0], 0.0);
  EXPECT_EQ(sim_->device().motor_force_n()[0], 0.0);
}

}  // namespace
}  // namespace visvol::haptic
