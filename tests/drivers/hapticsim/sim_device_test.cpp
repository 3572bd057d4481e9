// The simulated device (tools/hapticsim) on the in-process bus: protocol,
// watchdog, saturation, quantisation, dynamics, faults; and its scripts.
#include "drivers/hapticsim/sim_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "drivers/can/memory_bus.hpp"
#include "drivers/hapticsim/script.hpp"

namespace visvol::hapticsim {
namespace {

using haptic::Message;
using haptic::MessageKind;
using haptic::NmtState;
constexpr std::int64_t kMs = 1'000'000;
constexpr std::uint8_t kNode = 9;

class SimTest : public ::testing::Test {
 protected:
  void make(SimConfig c = SimConfig{}) {
    c.node_id = kNode;
    bus_.set_time_ns(now_);
    auto d = SimDevice::create(c, bus_.endpoint(1), now_);
    ASSERT_TRUE(d.ok()) << d.status().message();
    device_.emplace(std::move(d).value());
  }
  SimDevice& device() { return *device_; }
  can::CanBus& console() { return bus_.endpoint(0); }

  // Steps the device `ms` times; returns every frame it sent.
  std::vector<can::CanFrame> step(int ms) {
    std::vector<can::CanFrame> out;
    for (int i = 0; i < ms; ++i) {
      now_ += kMs;
      bus_.set_time_ns(now_);
      device().step(now_);
      can::CanFrame batch[16];
      for (std::size_t n; (n = console().receive(batch, 16)) > 0;) out.insert(out.end(), batch, batch + n);
    }
    return out;
  }
  void nmt(haptic::NmtCommand c, std::uint8_t node = kNode) {
    ASSERT_EQ(console().send(haptic::encode(haptic::NmtMsg{c, node})), Errc::ok);
  }
  void command(std::array<double, 3> f, bool enable = true) {
    ASSERT_EQ(console().send(haptic::encode(haptic::CommandMsg{f, enable, seq_++}, kNode)), Errc::ok);
  }
  void start() {
    step(1);
    nmt(haptic::NmtCommand::start);
    step(1);
    ASSERT_EQ(device().nmt_state(), NmtState::operational);
  }
  static std::vector<Message> decoded(const std::vector<can::CanFrame>& frames, MessageKind kind) {
    std::vector<Message> out;
    for (const can::CanFrame& f : frames) {
      Message m;
      if (haptic::decode(f, m) == haptic::DecodeError::ok && m.kind == kind) out.push_back(m);
    }
    return out;
  }

  can::MemoryBus bus_{2, 4096};
  std::optional<SimDevice> device_;
  std::int64_t now_ = 100 * kMs;
  std::uint8_t seq_ = 0;
};

TEST_F(SimTest, BootsIntoPreOperationalAndStartsOnNmt) {
  SimConfig c;
  c.boot_delay_ns = 20 * kMs;
  make(c);
  EXPECT_TRUE(step(19).empty()) << "powered off during the boot delay";
  auto frames = step(1);
  ASSERT_EQ(frames.size(), 1u);
  Message m;
  ASSERT_EQ(haptic::decode(frames[0], m), haptic::DecodeError::ok);
  EXPECT_EQ(m.kind, MessageKind::heartbeat);
  EXPECT_EQ(m.node, kNode);
  EXPECT_EQ(m.heartbeat.state, NmtState::boot_up);
  frames = step(200);
  const auto hbs = decoded(frames, MessageKind::heartbeat);
  EXPECT_EQ(hbs.size(), 4u) << "every 50 ms";
  for (const Message& h : hbs) EXPECT_EQ(h.heartbeat.state, NmtState::pre_operational);
  EXPECT_TRUE(decoded(frames, MessageKind::position).empty()) << "no positions before start";

  nmt(haptic::NmtCommand::start, 3);  // another node's start
  step(1);
  EXPECT_EQ(device().nmt_state(), NmtState::pre_operational);
  nmt(haptic::NmtCommand::start, 0);  // broadcast
  frames = step(100);
  EXPECT_EQ(device().nmt_state(), NmtState::operational);
  EXPECT_EQ(decoded(frames, MessageKind::position).size(), 100u);
  EXPECT_EQ(decoded(frames, MessageKind::status).size(), 10u);
  ASSERT_FALSE(decoded(frames, MessageKind::heartbeat).empty());
  EXPECT_EQ(decoded(frames, MessageKind::heartbeat)[0].heartbeat.state, NmtState::operational)
      << "a heartbeat at once on the change";
  const auto positions = decoded(frames, MessageKind::position);
  for (std::size_t i = 1; i < positions.size(); ++i) {
    EXPECT_EQ(static_cast<std::uint8_t>(positions[i].position.sequence - positions[i - 1].position.sequence), 1);
  }
  nmt(haptic::NmtCommand::stop);
  frames = step(100);
  EXPECT_EQ(device().nmt_state(), NmtState::stopped);
  EXPECT_TRUE(decoded(frames, MessageKind::position).empty());
}

TEST_F(SimTest, WatchdogZeroesForceTenMillisecondsAfterTheLastCommand) {
  make();
  start();
  for (int i = 0; i < 20; ++i) {
    command({0.0, 0.5, 0.0});
    step(1);
    EXPECT_NEAR(device().motor_force_n()[1], 0.5, 1e-9);
  }
  // Commands stop; the last arrived in the last step.
  for (int ms = 1; ms <= 12; ++ms) {
    step(1);
    if (ms < 10) {
      EXPECT_NEAR(device().motor_force_n()[1], 0.5, 1e-9) << ms;
    } else {
      EXPECT_EQ(device().motor_force_n()[1], 0.0) << ms;
    }
  }
  EXPECT_EQ(device().counters().watchdog_trips, 1u);
  const auto status = decoded(step(10), MessageKind::status);
  ASSERT_FALSE(status.empty());
  EXPECT_TRUE(status.back().status.flags & haptic::kStatusWatchdog);
  EXPECT_FALSE(status.back().status.flags & haptic::kStatusForceEnabled);
  // Enable off means zero force however large the command.
  command({0.0, 3.0, 0.0}, false);
  step(1);
  EXPECT_EQ(device().motor_force_n()[1], 0.0);
}

TEST_F(SimTest, SaturatesAtThePeakForceAlongTheCommand) {
  make();
  start();
  command({20.0, 0.0, -15.0});  // 25 N
  step(1);
  const auto& f = device().motor_force_n();
  EXPECT_NEAR(std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]), 8.5, 1e-9);
  EXPECT_NEAR(f[0] / f[2], -20.0 / 15.0, 1e-9);
  EXPECT_EQ(device().counters().saturated_steps, 1u);
  EXPECT_NEAR(device().counters().max_force_n, 8.5, 1e-9);
}

TEST_F(SimTest, HandleObeysNewtonAndQuantisesToTheEncoder) {
  SimConfig c;
  c.viscous_n_s_per_m = 0.0;
  c.coulomb_n = 0.0;
  make(c);
  Hand free;
  free.holding = false;
  device().set_hand(free);
  start();
  // 0.75 N on 75 g: 10 m/s^2; after 100 ms, 50 mm.
  for (int i = 0; i < 100; ++i) {
    command({0.75, 0.0, 0.0});
    step(1);
  }
  EXPECT_NEAR(device().position_mm()[0], 50.0, 1.5);
  const auto positions = decoded(step(1), MessageKind::position);
  ASSERT_EQ(positions.size(), 1u);
  const double x = positions[0].position.pos_mm[0];
  EXPECT_NEAR(x * 100.0, std::round(x * 100.0), 1e-9) << "whole 0.01 mm counts";
}

TEST_F(SimTest, DryFrictionHoldsTheHandleBelowItsThreshold) {
  SimConfig c;
  c.coulomb_n = 0.2;
  make(c);
  Hand free;
  free.holding = false;
  device().set_hand(free);
  start();
  for (int i = 0; i < 200; ++i) {
    command({0.15, 0.0, 0.0});
    step(1);
  }
  EXPECT_EQ(device().position_mm()[0], 0.0);
}

TEST_F(SimTest, HandPullsTheHandleToTheScriptedTarget) {
  make();
  Hand h;
  h.target_mm = {30.0, -10.0, 5.0};
  device().set_hand(h);
  step(1000);
  const auto p = device().position_mm();
  EXPECT_NEAR(p[0], 30.0, 0.2);
  EXPECT_NEAR(p[1], -10.0, 0.2);
  EXPECT_NEAR(p[2], 5.0, 0.2);
}

TEST_F(SimTest, OverheatingRaisesAnEmergencyAndCoolingClearsIt) {
  SimConfig c;
  c.thermal_time_s = 0.05;   // a fast motor model
  c.heating_c_per_n2 = 2.0;  // 8.5 N -> 25 + 144 degC
  make(c);
  start();
  std::vector<can::CanFrame> frames;
  for (int i = 0; i < 300; ++i) {
    command({8.5, 0.0, 0.0});
    const auto f = step(1);
    frames.insert(frames.end(), f.begin(), f.end());
  }
  EXPECT_TRUE(device().fault_bits() & haptic::kFaultOverTemperature);
  EXPECT_EQ(device().motor_force_n()[0], 0.0) << "no force while faulted";
  const auto emcy = decoded(frames, MessageKind::emergency);
  ASSERT_FALSE(emcy.empty());
  EXPECT_EQ(emcy[0].emergency.code, 0x4210);
  EXPECT_GT(emcy[0].emergency.temperature_c, 90.0);
  // Without force it cools, clears, and says so.
  frames = step(500);
  EXPECT_EQ(device().fault_bits(), 0);
  const auto reset = decoded(frames, MessageKind::emergency);
  ASSERT_FALSE(reset.empty());
  EXPECT_EQ(reset.back().emergency.code, 0x0000);
  EXPECT_EQ(reset.back().emergency.error_register, 0);
}

TEST_F(SimTest, InjectedFaultsShowOnTheBus) {
  make();
  start();
  step(20);
  // Silence: nothing at all.
  // Timed faults cover [now, now + duration): steps now + 1 .. now + duration - 1 ms.
  device().inject_silence(now_, 30 * kMs);
  EXPECT_TRUE(step(29).empty());
  EXPECT_FALSE(step(1).empty());
  // Freeze: the same frame, byte for byte.
  device().inject_freeze(now_, 6 * kMs);
  auto pos = decoded(step(5), MessageKind::position);
  ASSERT_EQ(pos.size(), 5u);
  for (const Message& m : pos) EXPECT_EQ(m.position.sequence, pos[0].position.sequence);
  // Wrong lengths: none of the device's own frames decodes.
  step(1);
  device().inject_wrong_length(now_, 20 * kMs);
  auto frames = step(19);
  EXPECT_FALSE(frames.empty());
  for (const can::CanFrame& f : frames) {
    Message m;
    EXPECT_EQ(haptic::decode(f, m), haptic::DecodeError::wrong_length);
  }
  // Garbage: N extra frames, mostly on this device's identifiers.
  device().inject_garbage(50);
  frames = step(50);
  EXPECT_EQ(device().counters().garbage_sent, 50u);
  EXPECT_GE(frames.size(), 100u);
  // Emergency: code, then reset.
  device().inject_emergency(now_, haptic::kFaultAmplifier, 10 * kMs);
  frames = step(20);
  auto emcy = decoded(frames, MessageKind::emergency);
  ASSERT_EQ(emcy.size(), 2u);
  EXPECT_EQ(emcy[0].emergency.code, 0x5000);
  EXPECT_EQ(emcy[1].emergency.code, 0x0000);
  // Bus-off: error frames around a silence; the console's endpoint receives error frames.
  bus_.endpoint(0).set_filters({}, true);
  device().inject_bus_off(now_, 10 * kMs);
  frames = step(1);
  ASSERT_FALSE(frames.empty());
  EXPECT_TRUE(can::classify_error(frames[0]).bus_off);
  frames = step(10);
  ASSERT_FALSE(frames.empty());
  EXPECT_TRUE(can::classify_error(frames[0]).restarted);
  // Reboot: silence, boot-up, pre-operational.
  device().inject_reboot(now_, 20 * kMs);
  EXPECT_TRUE(step(19).empty());
  frames = step(1);
  ASSERT_EQ(frames.size(), 1u);
  Message m;
  ASSERT_EQ(haptic::decode(frames[0], m), haptic::DecodeError::ok);
  EXPECT_EQ(m.heartbeat.state, NmtState::boot_up);
  EXPECT_EQ(device().nmt_state(), NmtState::pre_operational);
  EXPECT_EQ(device().counters().boots, 2u);
}

TEST_F(SimTest, DropsTheConfiguredFractionOfFrames) {
  SimConfig c;
  c.drop_fraction = 0.25;
  c.seed = 5;
  make(c);
  step(1);
  for (int i = 0; i < 20 && device().nmt_state() != NmtState::operational; ++i) {
    nmt(haptic::NmtCommand::start);
    step(1);
  }
  ASSERT_EQ(device().nmt_state(), NmtState::operational);
  const auto frames = step(4000);
  const double sent = static_cast<double>(decoded(frames, MessageKind::position).size());
  EXPECT_NEAR(sent / 4000.0, 0.75, 0.03);
}

TEST(SimConfigTest, RejectsBadValuesByName) {
  SimConfig c;
  c.mass_kg = 0.0;
  EXPECT_NE(SimDevice::validate(c).message().find("mass"), std::string::npos);
  c = SimConfig{};
  c.drop_fraction = 1.5;
  EXPECT_NE(SimDevice::validate(c).message().find("drop fraction"), std::string::npos);
  c = SimConfig{};
  c.node_id = 128;
  EXPECT_NE(SimDevice::validate(c).message().find("node id"), std::string::npos);
}

const std::array<double, 3> kHalf = {190.5, 133.5, 95.5};

TEST(Script, ErrorsNameTheLineAndTheProblem) {
  const auto error = [](const std::string& text) {
    auto s = parse_script(text, "s.txt", kHalf);
    return s.ok() ? std::string("(parsed)") : s.status().message();
  };
  EXPECT_EQ(error("0 grab\n0.5 fly 1\n"), "s.txt:2: unknown action 'fly'");
  EXPECT_EQ(error("1 grab\n0.5 release\n"), "s.txt:2: time 0.5 s is before the previous event's 1.000000 s");
  EXPECT_EQ(error("0 move 1 2 3\n"), "s.txt:1: 'move' takes 4 argument(s), got 3");
  EXPECT_EQ(error("0 move 1 2 nan 1\n"), "s.txt:1: distance 'nan' is not a finite number");
  EXPECT_EQ(error("0 move 0 0 100 1\n").find("s.txt:1: hand target 100"), 0u);
  EXPECT_EQ(error("0 pull 10 0 0 1\n0.5 pull 10 0 0 1\n").find("s.txt:2: motion starts at 0.5"), 0u);
  EXPECT_EQ(error("0 drop 1.5\n"), "s.txt:1: drop fraction 1.5 must lie in [0, 1]");
  EXPECT_EQ(error("0 silent 0\n").find("s.txt:1: duration 0 must lie in (0, "), 0u);
  EXPECT_EQ(error("0 emergency fire 1\n").find("s.txt:1: unknown emergency 'fire'"), 0u);
  EXPECT_EQ(error("0 garbage 2.5\n").find("s.txt:1: garbage frame count 2.5"), 0u);
  EXPECT_EQ(error("0 clutch maybe\n"), "s.txt:1: clutch takes 'on' or 'off', got 'maybe'");
  EXPECT_EQ(error("0 mode maybe\n"), "s.txt:1: mode takes 'on' or 'off', got 'maybe'");
  // strokes are held in memory: billions of them are refused, not queued
  EXPECT_EQ(error("0 drag 0 0 200000 1 0.0001\n").find("s.txt:1: a drag of 200000.000000 mm in strokes of"), 0u);
  EXPECT_NE(error("0 drag 0 0 1e9 1 0.001\n").find("more than 10000 strokes"), std::string::npos);
  {
    // nor do drags on many lines add up past a million events (3000 lines of
    // 10000 strokes asked 8.6 GB); back and forth, so the hand stays inside
    std::string many;
    for (int k = 0; k < 40; ++k) {
      many += std::to_string(k) + " drag " + (k % 2 ? "-" : "") + "599000 0 0 0.5 60\n";
    }
    EXPECT_NE(error(many).find("more than 1000000 events"), std::string::npos) << error(many);
  }
  EXPECT_EQ(error("0 mode\n"), "s.txt:1: 'mode' takes 1 argument(s), got 0");
  EXPECT_EQ(error("x grab\n"), "s.txt:1: time 'x' is not a finite number");
  EXPECT_EQ(error("0x1p3 grab\n"), "s.txt:1: time '0x1p3' is not a finite number");  // hexadecimal: not decimal
  EXPECT_EQ(error("  # only a comment\n\n0 grab # and another\n"), "(parsed)");
  auto missing = load_script("/nonexistent/script.txt", kHalf);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().message(), "/nonexistent/script.txt: cannot open the script: No such file or directory");
  EXPECT_EQ(missing.status().code(), Errc::invalid_argument);  // bad input: the console exits 2
}

TEST(Script, ExamplesParse) {
  for (const char* name : {"grab_pull_release.txt", "spool_drag.txt", "faults.txt"}) {
    auto s = load_script(std::string(VISVOL_HAPTICSIM_EXAMPLES) + "/" + name, kHalf);
    EXPECT_TRUE(s.ok()) << name << ": " << s.status().message();
    if (s.ok()) {
      EXPECT_TRUE(s->has_end) << name;
    }
  }
}

TEST(Script, DragIsStrokesReindexedWithTheClutch) {
  auto s = parse_script("0 drag 150 0 0 3 50\n", "s", kHalf);
  ASSERT_TRUE(s.ok()) << s.status().message();
  int clutch_on = 0, moves = 0, grabs = 0;
  for (const ScriptEvent& e : s->events) {
    clutch_on += e.action == Action::clutch_on;
    moves += e.action == Action::move;
    grabs += e.action == Action::grab;
  }
  EXPECT_EQ(grabs, 1);
  EXPECT_EQ(clutch_on, 2) << "three strokes, two returns";
  EXPECT_EQ(moves, 5);
  EXPECT_NEAR(s->end_s, 3.0, 1e-9);
  // Played back: the hand oscillates inside the workspace; the clutch is held on the way back.
  can::MemoryBus bus(1, 16);
  auto d = SimDevice::create(SimConfig{}, bus.endpoint(0), 0);
  ASSERT_TRUE(d.ok());
  Player player(*s);
  double max_x = 0.0;
  bool clutch_while_returning = false;
  double last_x = 0.0;
  for (int ms = 0; ms <= 3000; ++ms) {
    player.advance(ms * 1e-3, ms * kMs, *d);
    const Hand& h = d->hand();
    EXPECT_TRUE(h.grasp);
    max_x = std::max(max_x, h.target_mm[0]);
    if (h.target_mm[0] < last_x - 1e-9 && h.clutch) clutch_while_returning = true;
    if (h.target_mm[0] < last_x - 1e-9) {
      EXPECT_TRUE(h.clutch) << "moving back at " << ms << " ms";
    }
    last_x = h.target_mm[0];
  }
  EXPECT_NEAR(max_x, 50.0, 1e-9);
  EXPECT_NEAR(last_x, 50.0, 1e-9);
  EXPECT_TRUE(clutch_while_returning);
}

// `mode on|off` holds the third button (the console's pull / spool switch).
TEST(Script, ModePressesTheThirdButton) {
  auto s = parse_script("0.1 mode on\n0.2 mode off\n", "s", kHalf);
  ASSERT_TRUE(s.ok()) << s.status().message();
  can::MemoryBus bus(1, 16);
  auto d = SimDevice::create(SimConfig{}, bus.endpoint(0), 0);
  ASSERT_TRUE(d.ok());
  Player player(*s);
  player.advance(0.05, 50 * kMs, *d);
  EXPECT_FALSE(d->hand().mode);
  player.advance(0.15, 150 * kMs, *d);
  EXPECT_TRUE(d->hand().mode);
  EXPECT_FALSE(d->hand().grasp);
  EXPECT_FALSE(d->hand().clutch);
  player.advance(0.25, 250 * kMs, *d);
  EXPECT_FALSE(d->hand().mode);
}

}  // namespace
}  // namespace visvol::hapticsim
