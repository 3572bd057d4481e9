// Safety properties of the whole console path (driver + servo) against the
// simulated device on the in-process bus, in simulated time with 1 ms ticks:
// force never above the limit, zero within 10 ms of silence, no jump on
// re-enable, forces back only after a new grasp, recovery from every fault the
// simulator injects; and no allocation or page fault in the console's tick.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <optional>
#include <random>
#include <sstream>

#include "drivers/can/memory_bus.hpp"
#include "drivers/hapticsim/script.hpp"
#include "drivers/hapticsim/sim_device.hpp"
#include "tests/drivers/haptic/console_harness.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::testing {
namespace {

using haptic::DeviceState;
using haptic::FaultReason;
constexpr std::int64_t kMs = 1'000'000;

class Rig {
 public:
  explicit Rig(const std::string& script_text, std::uint8_t node = 1, double drop = 0.0, std::uint64_t seed = 1)
      : bus_(3, 4096) {
    bus_.set_time_ns(start_ns_);
    bus_.endpoint(0).set_filters(haptic::DeviceDriver::receive_filters(node), true);
    bus_.endpoint(1).set_filters({{haptic::frame_id(haptic::MessageKind::command, node), 0x7FF}, {0, 0x7FF}}, false);
    bus_.endpoint(2).set_filters({}, true);  // the tap: everything, like candump

    hapticsim::SimConfig sc;
    sc.node_id = node;
    sc.drop_fraction = drop;
    sc.seed = seed;
    auto device = hapticsim::SimDevice::create(sc, bus_.endpoint(1), start_ns_);
    EXPECT_TRUE(device.ok()) << device.status().message();
    device_.emplace(std::move(device).value());
    auto script = hapticsim::parse_script(script_text, "test script", sc.workspace_half_mm);
    EXPECT_TRUE(script.ok()) << script.status().message();
    script_ = std::move(script).value();
    player_.emplace(script_);

    haptic::DriverConfig dc;
    dc.node_id = node;
    auto driver = haptic::DeviceDriver::create(dc, bus_.endpoint(0));
    auto servo = servo::Servo::create(test_servo_config());
    EXPECT_TRUE(driver.ok() && servo.ok());
    console_.emplace(std::move(driver).value(), std::move(servo).value());
    limits_.node = node;
  }

  // Runs `seconds` of 1 ms ticks: device first, then the console, then the tap.
  void run(double seconds) {
    const int steps = static_cast<int>(seconds * 1000.0 + 0.5);
    for (int k = 0; k < steps; ++k) {
      now_ns_ += kMs;
      bus_.set_time_ns(now_ns_);
      player_->advance(static_cast<double>(now_ns_ - start_ns_) * 1e-9, now_ns_, *device_);
      device_->step(now_ns_);
      motor_.push_back(haptic::PositionMsg{device_->motor_force_n(), 0, 0}.pos_mm);
      ticks_.push_back(console_->tick(now_ns_));
      can::CanFrame batch[16];
      for (std::size_t n; (n = bus_.endpoint(2).receive(batch, 16)) > 0;) {
        for (std::size_t i = 0; i < n; ++i) frames_.push_back({batch[i].timestamp_ns, batch[i]});
      }
    }
  }

  // Runs without recording anything; returns the allocations and minor page
  // faults that happened inside the console's ticks.
  std::pair<std::uint64_t, long> run_measured(double seconds) {
    std::uint64_t allocations = 0;
    long page_faults = 0;
    can::CanFrame batch[16];
    const int steps = static_cast<int>(seconds * 1000.0 + 0.5);
    for (int k = 0; k < steps; ++k) {
      now_ns_ += kMs;
      bus_.set_time_ns(now_ns_);
      player_->advance(static_cast<double>(now_ns_ - start_ns_) * 1e-9, now_ns_, *device_);
      device_->step(now_ns_);
      rusage before{}, after{};
      getrusage(RUSAGE_THREAD, &before);
      const std::uint64_t allocs = allocation_count();
      console_->tick(now_ns_);
      allocations += allocation_count() - allocs;
      getrusage(RUSAGE_THREAD, &after);
      page_faults += after.ru_minflt - before.ru_minflt;
      while (bus_.endpoint(2).receive(batch, 16) > 0) {
      }
    }
    return {allocations, page_faults};
  }

  // Every invariant; returns the number of non-zero force commands.
  int check() {
    const int nonzero = check_console_traffic(frames_, limits_);
    check_console_ticks(ticks_);
    EXPECT_LE(device_->counters().max_force_n, limits_.max_force_n + 1e-9);
    return nonzero;
  }

  double t_s(std::size_t tick) const { return static_cast<double>(ticks_[tick].t_ns - start_ns_) * 1e-9; }
  std::size_t tick_at(double t_s) const { return static_cast<std::size_t>(t_s * 1000.0 + 0.5) - 1; }

  Console& console() { return *console_; }
  hapticsim::SimDevice& device() { return *device_; }
  const std::vector<ConsoleTick>& ticks() const { return ticks_; }
  const std::vector<BusFrame>& frames() const { return frames_; }
  const std::vector<std::array<double, 3>>& motor() const { return motor_; }
  std::int64_t start_ns() const { return start_ns_; }

 private:
  can::MemoryBus bus_;
  std::int64_t start_ns_ = 5'000 * kMs;
  std::int64_t now_ns_ = start_ns_;
  std::optional<hapticsim::SimDevice> device_;
  hapticsim::Script script_;
  std::optional<hapticsim::Player> player_;
  std::optional<Console> console_;
  TrafficLimits limits_;
  std::vector<BusFrame> frames_;
  std::vector<ConsoleTick> ticks_;
  std::vector<std::array<double, 3>> motor_;
};

double max_force(const std::vector<ConsoleTick>& ticks, std::size_t from, std::size_t to) {
  double m = 0.0;
  for (std::size_t i = from; i < to && i < ticks.size(); ++i) m = std::max(m, ticks[i].out.device_force_n.norm());
  return m;
}

TEST(Safety, GrabPullReleaseFeelsTheRopeWithinTheClamp) {
  Rig rig(R"(
    0.20 pull 40 0 0 0.5    # grab the rope and pull it 40 mm right (0.4 m east)
    1.20 release
    1.50 end
  )");
  rig.run(1.0);
  EXPECT_GT(rig.console().rope().pos_m.x(), 0.05) << "the rope followed the pull east";
  rig.run(0.5);
  EXPECT_GT(rig.check(), 300);
  const auto& ticks = rig.ticks();
  // Operational within a few ticks of the first heartbeat.
  std::size_t first_op = 0;
  while (first_op < ticks.size() && ticks[first_op].state != DeviceState::operational) ++first_op;
  EXPECT_LT(first_op, 10u);
  // The hand is pulled back (device -x), up to the clamp, and the device applies it.
  const ConsoleTick& pulled = ticks[rig.tick_at(1.0)];
  EXPECT_NEAR(pulled.out.device_force_n.norm(), 1.4, 1e-9);
  EXPECT_LT(pulled.out.device_force_n.x(), -1.3);
  EXPECT_NEAR(rig.motor()[rig.tick_at(1.0)][0], pulled.out.device_force_n.x(), 2e-3) << "one tick later at the device";
  EXPECT_GT(rig.device().counters().saturated_steps + rig.device().counters().force_steps, 500u);
  EXPECT_EQ(rig.device().counters().saturated_steps, 0u) << "the console's clamp is below the device's";
  // Released: force down to zero within 1.4 N / 100 N/s = 14 ms (plus a tick).
  EXPECT_EQ(max_force(ticks, rig.tick_at(1.2) + 16, ticks.size()), 0.0);
}

TEST(Safety, SilenceZeroesTheCommandWithinTenMillisecondsAndTheDeviceToo) {
  Rig rig(R"(
    0.10 pull 30 0 0 0.3
    1.00 silent 0.3
    1.50 release
    1.60 grab
    2.20 end
  )");
  rig.run(2.2);
  rig.check();
  const auto& ticks = rig.ticks();
  ASSERT_GT(ticks[rig.tick_at(0.99)].out.device_force_n.norm(), 1.0);
  // The last position left the device at 0.999 s (the 1.000 s step is already silent).
  for (std::size_t i = rig.tick_at(1.000); i < rig.tick_at(1.3); ++i) {
    const double since_ms = rig.t_s(i) * 1000.0 - 999.0;
    if (since_ms >= 10.0) {
      EXPECT_EQ(ticks[i].out.device_force_n.norm(), 0.0) << since_ms << " ms after the last position";
      // Position timeout first; 200 ms after the last status, the device is lost.
      EXPECT_TRUE(ticks[i].fault == FaultReason::position_timeout ||
                  (since_ms > 185.0 && ticks[i].fault == FaultReason::heartbeat_lost))
          << haptic::fault_name(ticks[i].fault) << " at " << since_ms << " ms";
    }
    // The device got its last command at 1.000 s at the latest: zero 10 ms later.
    if (rig.t_s(i) >= 1.010) {
      EXPECT_EQ(norm3(rig.motor()[i]), 0.0) << rig.t_s(i);
    }
  }
  EXPECT_GE(rig.device().counters().watchdog_trips, 1u);
  // Back on the bus at 1.3 s with the button still held: no force until the new grasp at 1.6 s.
  EXPECT_EQ(ticks[rig.tick_at(1.35)].state, DeviceState::operational);
  EXPECT_EQ(max_force(ticks, rig.tick_at(1.0) + 10, rig.tick_at(1.6)), 0.0);
  EXPECT_GT(max_force(ticks, rig.tick_at(1.6), ticks.size()), 1.0) << "forces return after the new grasp";
}

TEST(Safety, ReEnableRampsFromZeroWithoutAJump) {
  Rig rig(R"(
    0.10 pull 30 0 0 0.2
    0.60 reboot 0.1
    1.00 release
    1.05 grab
    1.60 end
  )");
  rig.run(1.6);
  rig.check();  // includes the slew check on every command
  const auto& ticks = rig.ticks();
  EXPECT_EQ(rig.console().driver().counters().device_reboots, 1u);
  std::size_t first = rig.tick_at(1.05);
  while (first < ticks.size() && ticks[first].out.device_force_n.norm() == 0.0) ++first;
  ASSERT_LT(first, ticks.size());
  EXPECT_LE(ticks[first].out.device_force_n.norm(), 0.1 + 1e-12) << "the first step after re-enable";
  EXPECT_GT(max_force(ticks, first, ticks.size()), 1.0);
}

TEST(Safety, RecoversFromEveryInjectedFault) {
  struct Case {
    const char* name;
    const char* fault;
    FaultReason expect;  // a fault the console must have passed through
  };
  const Case cases[] = {
      {"silent", "0.50 silent 0.25", FaultReason::position_timeout},
      {"freeze", "0.50 freeze 0.2", FaultReason::position_timeout},
      {"wrong-length", "0.50 wrong-length 0.2", FaultReason::position_timeout},
      {"reboot", "0.50 reboot 0.2", FaultReason::position_timeout},
      {"bus-off", "0.50 bus-off 0.3", FaultReason::bus_off},
      {"emergency", "0.50 emergency over-temperature 0.2", FaultReason::device_fault},
      {"long silence", "0.50 silent 0.5", FaultReason::heartbeat_lost},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Rig rig(std::string("0.10 pull 20 0 0 0.2\n") + c.fault + "\n1.40 release\n1.45 grab\n2.00 end\n");
    rig.run(2.0);
    rig.check();
    const auto& ticks = rig.ticks();
    bool saw = false;
    for (const ConsoleTick& t : ticks) saw = saw || t.fault == c.expect;
    EXPECT_TRUE(saw) << haptic::fault_name(c.expect);
    EXPECT_EQ(ticks[rig.tick_at(1.4)].state, DeviceState::operational) << "recovered by itself";
    EXPECT_GT(max_force(ticks, rig.tick_at(1.45), ticks.size()), 0.5) << "and forces return after a new grasp";
    EXPECT_EQ(max_force(ticks, rig.tick_at(0.5) + 11, rig.tick_at(1.45)), 0.0) << "none before it";
  }
}

TEST(Safety, BusOffAndEmergencyAreDecodedAndCounted) {
  Rig rig("0.3 bus-off 0.2\n0.8 emergency encoder 0.1\n1.2 end\n");
  rig.run(1.2);
  rig.check();
  const auto& c = rig.console().driver().counters();
  EXPECT_EQ(c.bus_off, 1u);
  EXPECT_EQ(c.bus_restarts, 1u);
  EXPECT_EQ(c.emergencies, 2u) << "the fault and its reset";
  EXPECT_EQ(rig.console().driver().report().last_emergency.code, 0x0000);
  EXPECT_EQ(rig.console().driver().state(), DeviceState::operational);
}

TEST(Safety, GarbageIsCountedAndHarmless) {
  Rig rig("0.10 pull 20 0 0 0.2\n0.5 garbage 300\n1.2 end\n");
  rig.run(1.2);
  const int nonzero = rig.check();
  EXPECT_GT(nonzero, 100);
  const auto& c = rig.console().driver().counters();
  EXPECT_GT(c.malformed + c.implausible + c.duplicates, 0u);
  EXPECT_EQ(rig.console().driver().state(), DeviceState::operational);
}

// A random operator with random faults, many times: the invariants always hold.
std::string random_script(std::mt19937_64& rng, double length_s) {
  std::ostringstream s;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double t = 0.05, motion_end = 0.0;
  std::array<double, 3> target{};
  while (t < length_s - 0.1) {
    const int kind = static_cast<int>(rng() % 12);
    s << t << ' ';
    if (kind <= 3 && t >= motion_end) {
      const double dur = 0.05 + 0.4 * u(rng);
      std::array<double, 3> d{};
      for (std::size_t i = 0; i < 3; ++i) {
        d[i] = -40.0 + 80.0 * u(rng);
        if (std::fabs(target[i] + d[i]) > 80.0) d[i] = -d[i];
        target[i] += d[i];
      }
      s << (kind == 0 ? "drag " : "pull ") << d[0] << ' ' << d[1] << ' ' << d[2] << ' ' << dur;
      if (kind == 0) {  // a drag ends one stroke (of at most 60 mm) from its start
        const double strokes = std::max(1.0, std::ceil(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / 60.0));
        for (std::size_t i = 0; i < 3; ++i) target[i] -= d[i] - d[i] / strokes;
      }
      motion_end = t + dur;
    } else if (kind == 4) {
      s << "release";
    } else if (kind == 5) {
      s << "grab";
    } else if (kind == 6) {
      s << (u(rng) < 0.5 ? "clutch on" : "clutch off");
    } else {
      const char* faults[] = {"silent", "freeze", "wrong-length", "bus-off", "reboot"};
      const int f = static_cast<int>(rng() % 8);
      if (f < 5) {
        s << faults[f] << ' ' << 0.005 + 0.25 * u(rng);
      } else if (f == 5) {
        s << "garbage " << 1 + rng() % 40;
      } else if (f == 6) {
        s << "drop " << 0.3 * u(rng);
      } else {
        const char* kinds[] = {"over-current", "over-temperature", "amplifier", "encoder"};
        s << "emergency " << kinds[rng() % 4] << ' ' << 0.01 + 0.2 * u(rng);
      }
    }
    s << '\n';
    t += 0.02 + 0.25 * u(rng);
  }
  s << length_s << " end\n";
  return s.str();
}

TEST(Safety, PropertyInvariantsHoldForRandomOperatorsAndFaults) {
  std::mt19937_64 rng(2024);
  int total_nonzero = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::string script = random_script(rng, 3.0);
    SCOPED_TRACE("trial " + std::to_string(trial) + ":\n" + script);
    Rig rig(script, static_cast<std::uint8_t>(1 + trial % 127), 0.0, rng());
    rig.run(3.0);
    total_nonzero += rig.check();
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(total_nonzero, 1000) << "the random operators did pull on the rope";
}

TEST(Safety, ConsoleTickNeitherAllocatesNorFaultsPages) {
  Rig rig("0.1 pull 20 0 0 0.5\n1.5 clutch on\n1.6 clutch off\n2.2 silent 0.05\n9.0 end\n");
  rig.run_measured(1.0);  // warm-up: every buffer and page touched once
  const auto [allocations, page_faults] = rig.run_measured(2.0);
  EXPECT_EQ(allocations, 0u);
#ifndef VISVOL_SANITIZED
  EXPECT_EQ(page_faults, 0) << "minor page faults inside console ticks";
#endif
  EXPECT_GT(rig.device().counters().force_steps, 500u) << "the measured ticks did real work";
}

}  // namespace
}  // namespace visvol::testing
