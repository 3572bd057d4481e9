// The console-side state machine against a hand-driven fake device on the
// in-process bus, in simulated time (1 ms ticks).
#include "drivers/haptic/device_driver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "drivers/can/memory_bus.hpp"

namespace visvol::haptic {
namespace {

constexpr std::uint8_t kNode = 3;
constexpr std::int64_t kMs = 1'000'000;

class DriverTest : public ::testing::Test {
 protected:
  DriverTest() : bus_(2, 512) {
    bus_.set_time_ns(now_);
    bus_.endpoint(0).set_filters(DeviceDriver::receive_filters(kNode), true);
    DriverConfig c;
    c.node_id = kNode;
    auto d = DeviceDriver::create(c, bus_.endpoint(0));
    EXPECT_TRUE(d.ok()) << d.status().message();
    driver_.emplace(std::move(d).value());
  }

  can::CanBus& device() { return bus_.endpoint(1); }
  DeviceDriver& driver() { return *driver_; }

  // Sends a device frame stamped with the current time.
  void heartbeat(NmtState s) { ASSERT_EQ(device().send(encode(HeartbeatMsg{s}, kNode)), Errc::ok); }
  void status(NmtState s, std::uint16_t faults = 0) {
    StatusMsg m;
    m.nmt_state = s;
    m.fault_bits = faults;
    m.sequence = status_seq_++;
    ASSERT_EQ(device().send(encode(m, kNode)), Errc::ok);
  }
  void position(std::array<double, 3> mm, std::uint8_t buttons = 0) {
    ASSERT_EQ(device().send(encode(PositionMsg{mm, buttons, pos_seq_++}, kNode)), Errc::ok);
  }
  void emergency(std::uint16_t code, std::uint8_t reg) {
    EmergencyMsg e;
    e.code = code;
    e.error_register = reg;
    ASSERT_EQ(device().send(encode(e, kNode)), Errc::ok);
  }
  void error_frame(std::uint32_t classes) {
    can::CanFrame f;
    f.flags = can::CanFrame::kError;
    f.id = classes;
    f.len = 8;
    bus_.inject(f);
  }

  // One console tick at the current time; returns the frames it sent.
  std::vector<Message> tick(const std::array<double, 3>& force_n = {0, 0, 0}, bool enable = false) {
    driver().poll(now_);
    (void)driver().command(force_n, enable);
    std::vector<Message> sent;
    can::CanFrame batch[16];
    for (std::size_t n; (n = device().receive(batch, 16)) > 0;) {
      for (std::size_t i = 0; i < n; ++i) {
        if (batch[i].is_error()) continue;  // injected error frames reach every endpoint
        Message m;
        EXPECT_EQ(decode(batch[i], m), DecodeError::ok) << "the console sends only valid frames";
        sent.push_back(m);
      }
    }
    return sent;
  }
  void advance(std::int64_t ns) {
    now_ += ns;
    bus_.set_time_ns(now_);
  }
  static int count(const std::vector<Message>& v, MessageKind k) {
    int n = 0;
    for (const Message& m : v) n += m.kind == k;
    return n;
  }

  // Brings the driver to operational through the normal start-up.
  void start_up() {
    heartbeat(NmtState::pre_operational);
    const auto sent = tick();
    ASSERT_EQ(driver().state(), DeviceState::pre_operational);
    ASSERT_EQ(count(sent, MessageKind::nmt), 1);
    advance(kMs);
    heartbeat(NmtState::operational);
    position({1, 2, 3});
    tick();
    ASSERT_EQ(driver().state(), DeviceState::operational);
  }
  void stream(int ms, std::array<double, 3> mm = {1, 2, 3}) {
    for (int i = 0; i < ms; ++i) {
      advance(kMs);
      position(mm);
      if (i % 10 == 0) status(NmtState::operational);
      tick();
    }
  }

  can::MemoryBus bus_;
  std::optional<DeviceDriver> driver_;
  std::int64_t now_ = 1'000 * kMs;
  std::uint8_t pos_seq_ = 0;
  std::uint8_t status_seq_ = 0;
};

TEST(DriverConfigTest, NamesTheBadField) {
  DriverConfig c;
  c.node_id = 0;
  EXPECT_NE(DeviceDriver::validate(c).message().find("node_id"), std::string::npos);
  c = DriverConfig{};
  c.position_timeout_ns = 0;
  EXPECT_NE(DeviceDriver::validate(c).message().find("position_timeout_ns"), std::string::npos);
  c = DriverConfig{};
  c.max_force_n = std::nan("");
  EXPECT_NE(DeviceDriver::validate(c).message().find("max_force_n"), std::string::npos);
  c = DriverConfig{};
  c.heartbeat_timeout_ns = 10 * kMs;
  EXPECT_NE(DeviceDriver::validate(c).message().find("heartbeat_timeout_ns"), std::string::npos);
  EXPECT_TRUE(DeviceDriver::validate(DriverConfig{}).ok());
}

TEST_F(DriverTest, BootSendsNothingUntilTheDeviceSpeaks) {
  for (int i = 0; i < 50; ++i) {
    advance(kMs);
    EXPECT_TRUE(tick({1, 1, 1}, true).empty());
  }
  EXPECT_EQ(driver().state(), DeviceState::boot);
  EXPECT_FALSE(driver().sample().valid);
}

TEST_F(DriverTest, StartsTheDeviceAndCommandsForceOnlyWhenOperational) {
  heartbeat(NmtState::boot_up);
  auto sent = tick({1, 0, 0}, true);
  EXPECT_EQ(driver().state(), DeviceState::pre_operational);
  ASSERT_EQ(count(sent, MessageKind::nmt), 1);
  EXPECT_EQ(sent[0].nmt.command, NmtCommand::start);
  EXPECT_EQ(sent[0].nmt.node, kNode) << "addressed to this node only, not broadcast";
  ASSERT_EQ(count(sent, MessageKind::command), 1);
  EXPECT_FALSE(sent[1].command.enable) << "zero command while pre-operational";
  EXPECT_EQ(sent[1].command.force_n[0], 0.0);
  EXPECT_EQ(driver().counters().device_reboots, 0u) << "the first boot-up is no reboot";

  // NMT start repeats every 100 ms until the device is operational.
  int nmt = 0;
  for (int i = 0; i < 250; ++i) {
    advance(kMs);
    if (i % 50 == 0) heartbeat(NmtState::pre_operational);
    nmt += count(tick(), MessageKind::nmt);
  }
  EXPECT_EQ(nmt, 2);

  // Operational by heartbeat, but no position yet: still waiting.
  advance(kMs);
  heartbeat(NmtState::operational);
  tick();
  EXPECT_EQ(driver().state(), DeviceState::pre_operational);
  advance(kMs);
  position({10, -20, 30}, kButtonGrasp);
  sent = tick({0.5, -0.25, 2.0}, true);
  EXPECT_EQ(driver().state(), DeviceState::operational);
  EXPECT_TRUE(driver().sample().valid);
  EXPECT_TRUE(driver().sample().fresh);
  EXPECT_DOUBLE_EQ(driver().sample().pos_mm[1], -20.0);
  EXPECT_EQ(driver().sample().buttons, kButtonGrasp);
  ASSERT_EQ(count(sent, MessageKind::command), 1);
  EXPECT_TRUE(sent.back().command.enable);
  EXPECT_NEAR(sent.back().command.force_n[2], 2.0, 1e-12);
  EXPECT_NEAR(sent.back().command.force_n[1], -0.25, 1e-12);
}

TEST_F(DriverTest, PositionSilenceZeroesTheCommandAtTenMilliseconds) {
  start_up();
  stream(20);
  const std::int64_t last_position_ns = now_;
  for (int i = 1; i <= 15; ++i) {
    advance(kMs);
    const auto sent = tick({1, 1, 1}, true);
    ASSERT_EQ(sent.size(), 1u);
    if (now_ - last_position_ns < 10 * kMs) {
      EXPECT_TRUE(sent[0].command.enable) << i << " ms";
      EXPECT_EQ(driver().state(), DeviceState::operational);
    } else {
      EXPECT_FALSE(sent[0].command.enable) << i << " ms";
      EXPECT_EQ(sent[0].command.force_n, (std::array<double, 3>{0, 0, 0}));
      EXPECT_EQ(driver().state(), DeviceState::fault);
      EXPECT_EQ(driver().fault(), FaultReason::position_timeout);
    }
  }
  EXPECT_EQ(driver().counters().faults[static_cast<std::size_t>(FaultReason::position_timeout)], 1u);
  // Positions again: operational again.
  advance(kMs);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
}

TEST_F(DriverTest, RepeatedSequenceNumbersAreNoNewSamples) {
  start_up();
  stream(5);
  // A frozen device repeats its last frame verbatim.
  const std::uint8_t frozen = static_cast<std::uint8_t>(pos_seq_ - 1);
  for (int i = 0; i < 12; ++i) {
    advance(kMs);
    ASSERT_EQ(device().send(encode(PositionMsg{{1, 2, 3}, 0, frozen}, kNode)), Errc::ok);
    tick();
    EXPECT_FALSE(driver().sample().fresh);
  }
  EXPECT_EQ(driver().fault(), FaultReason::position_timeout);
  EXPECT_EQ(driver().counters().duplicates, 12u);
}

TEST_F(DriverTest, CountsSequenceGapsAndRejectsImplausiblePositions) {
  start_up();
  stream(3);
  pos_seq_ = static_cast<std::uint8_t>(pos_seq_ + 4);  // four frames lost
  stream(1);
  EXPECT_EQ(driver().counters().sequence_gaps, 4u);
  // A 50 mm jump within 1 ms is no hand motion.
  advance(kMs);
  position({51, 2, 3});
  tick();
  EXPECT_FALSE(driver().sample().fresh);
  EXPECT_DOUBLE_EQ(driver().sample().pos_mm[0], 1.0);
  // Beyond the position limit.
  advance(kMs);
  position({1, 2, 300});
  tick();
  EXPECT_EQ(driver().counters().implausible, 2u);
  // A legitimate 4 mm step per ms (4 m/s) passes.
  advance(kMs);
  position({5, 2, 3});
  tick();
  EXPECT_TRUE(driver().sample().fresh);
}

TEST_F(DriverTest, MalformedAndForeignFramesAreCountedAndIgnored) {
  start_up();
  can::CanFrame bad = encode(PositionMsg{{50, 50, 50}, 0, 77}, kNode);
  bad.len = 6;
  ASSERT_EQ(device().send(bad), Errc::ok);
  can::CanFrame reserved = encode(PositionMsg{{50, 50, 50}, 0, 78}, kNode);
  reserved.data[6] = 0x80;
  ASSERT_EQ(device().send(reserved), Errc::ok);
  tick();
  EXPECT_EQ(driver().counters().malformed, 2u);
  EXPECT_DOUBLE_EQ(driver().sample().pos_mm[0], 1.0);
  // Another node's frames do not pass the filters; with no filters they are foreign.
  bus_.endpoint(0).set_filters({}, true);
  ASSERT_EQ(device().send(encode(PositionMsg{{9, 9, 9}, 0, 1}, kNode + 1)), Errc::ok);
  ASSERT_EQ(device().send(encode(CommandMsg{{1, 1, 1}, true, 0}, kNode)), Errc::ok);
  tick();
  EXPECT_EQ(driver().counters().foreign, 2u);
  EXPECT_DOUBLE_EQ(driver().sample().pos_mm[0], 1.0);
}

TEST_F(DriverTest, HeartbeatLossIsAFaultAndContactRecovers) {
  start_up();
  // Positions alone do not keep the device alive: heartbeat or status must.
  for (int i = 0; i < 199; ++i) {
    advance(kMs);
    position({1, 2, 3});
    tick();
  }
  EXPECT_EQ(driver().state(), DeviceState::operational);
  advance(kMs);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().fault(), FaultReason::heartbeat_lost);
  advance(kMs);
  status(NmtState::operational);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
}

TEST_F(DriverTest, EmergencyFaultsUntilResetAndNamesTheCode) {
  start_up();
  stream(5);
  advance(kMs);
  emergency(0x4210, 0x09);
  position({1, 2, 3});
  const auto sent = tick({1, 0, 0}, true);
  EXPECT_EQ(driver().fault(), FaultReason::device_fault);
  EXPECT_FALSE(sent.back().command.enable) << "zero in the tick the emergency arrives";
  EXPECT_STREQ(emergency_name(driver().report().last_emergency.code), "over-temperature");
  stream(30);  // clean status would clear only after 50 ms
  EXPECT_EQ(driver().fault(), FaultReason::device_fault);
  advance(kMs);
  emergency(0x0000, 0x00);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
  EXPECT_EQ(driver().counters().emergencies, 2u);
}

TEST_F(DriverTest, CleanStatusClearsAnEmergencyWhoseResetWasLost) {
  start_up();
  advance(kMs);
  emergency(0x2310, 0x03);
  tick();
  ASSERT_EQ(driver().fault(), FaultReason::device_fault);
  int ms = 0;
  while (driver().state() != DeviceState::operational && ms < 200) {
    stream(1);
    ++ms;
  }
  EXPECT_GE(ms, 50) << "not before 50 ms of clean status";
  EXPECT_LE(ms, 62);
}

TEST_F(DriverTest, StatusFaultBitsAreAFaultEvenWithoutEmergency) {
  start_up();
  advance(kMs);
  status(NmtState::operational, 0x0400);  // an unknown bit is a fault too
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().fault(), FaultReason::device_fault);
  advance(kMs);
  status(NmtState::operational, 0);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
}

TEST_F(DriverTest, RecoversAfterADeviceReboot) {
  start_up();
  stream(10);
  // The device reboots: silence, then boot-up and pre-operational.
  for (int i = 0; i < 30; ++i) {
    advance(kMs);
    tick();
  }
  EXPECT_EQ(driver().fault(), FaultReason::position_timeout);
  advance(kMs);
  heartbeat(NmtState::boot_up);
  auto sent = tick();
  EXPECT_EQ(driver().counters().device_reboots, 1u);
  EXPECT_EQ(driver().state(), DeviceState::pre_operational);
  EXPECT_EQ(count(sent, MessageKind::nmt), 1);
  advance(kMs);
  heartbeat(NmtState::operational);
  pos_seq_ = 0;          // a rebooted device counts from 0 again
  position({40, 2, 3});  // and may report any position
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
  EXPECT_DOUBLE_EQ(driver().sample().pos_mm[0], 40.0);
}

TEST_F(DriverTest, DeviceLeavingOperationalStopsForceAndIsRestarted) {
  start_up();
  stream(5);
  advance(kMs);
  heartbeat(NmtState::pre_operational);
  position({1, 2, 3});
  const auto sent = tick({1, 0, 0}, true);
  EXPECT_EQ(driver().state(), DeviceState::pre_operational);
  EXPECT_EQ(count(sent, MessageKind::nmt), 1);
  EXPECT_FALSE(sent.back().command.enable);
}

TEST_F(DriverTest, BusOffSilencesTheConsoleUntilRestarted) {
  start_up();
  stream(5);
  advance(kMs);
  error_frame(can::err::kBusOff);
  EXPECT_TRUE(tick({1, 0, 0}, true).empty()) << "nothing is sent while bus-off";
  EXPECT_EQ(driver().fault(), FaultReason::bus_off);
  EXPECT_EQ(driver().command({1, 0, 0}, true), Errc::state);
  for (int i = 0; i < 300; ++i) {
    advance(kMs);
    EXPECT_TRUE(tick().empty());
  }
  EXPECT_EQ(driver().fault(), FaultReason::bus_off) << "bus-off outranks the lost heartbeat";
  advance(kMs);
  error_frame(can::err::kRestarted);
  tick();
  EXPECT_EQ(driver().fault(), FaultReason::heartbeat_lost) << "back on the bus, the device not heard yet";
  advance(kMs);
  status(NmtState::operational);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
  EXPECT_EQ(driver().counters().bus_off, 1u);
  EXPECT_EQ(driver().counters().bus_restarts, 1u);
}

TEST_F(DriverTest, AnyDeviceFrameEndsBusOffWhenTheRestartWasMissed) {
  start_up();
  advance(kMs);
  error_frame(can::err::kBusOff);
  tick();
  ASSERT_EQ(driver().fault(), FaultReason::bus_off);
  advance(kMs);
  status(NmtState::operational);
  position({1, 2, 3});
  tick();
  EXPECT_EQ(driver().state(), DeviceState::operational);
}

TEST_F(DriverTest, CommandsAreClampedAndNonFiniteForcesRejected) {
  start_up();
  advance(kMs);
  position({1, 2, 3});
  auto sent = tick({30.0, 0.0, 40.0}, true);  // 50 N
  ASSERT_EQ(sent.size(), 1u);
  const auto& f = sent[0].command.force_n;
  EXPECT_LE(std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]), 8.5);
  EXPECT_NEAR(f[0] / f[2], 0.75, 1e-3) << "direction kept";
  EXPECT_EQ(driver().counters().clamped_commands, 1u);
  advance(kMs);
  position({1, 2, 3});
  sent = tick({std::nan(""), 0.0, 1.0}, true);
  EXPECT_FALSE(sent[0].command.enable);
  EXPECT_EQ(sent[0].command.force_n[2], 0.0);
  EXPECT_EQ(driver().counters().rejected_commands, 1u);
}

TEST_F(DriverTest, DrainsAFloodUpToTheCapAndCountsIt) {
  start_up();
  for (int i = 0; i < 400; ++i) status(NmtState::operational);
  advance(kMs);
  driver().poll(now_);
  EXPECT_EQ(driver().counters().capped_polls, 1u);
  driver().poll(now_);
  EXPECT_EQ(driver().counters().capped_polls, 1u) << "the rest drained in the next poll";
}

}  // namespace
}  // namespace visvol::haptic
