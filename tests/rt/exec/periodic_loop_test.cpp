// The periodic loop's mechanisms: absolute deadlines, overrun counting, the
// safe state after a run of overruns, skipped deadlines, reports. No timing
// bound is asserted (the machine is shared): only what the loop must count.
#include "rt/exec/periodic_loop.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "tests/support/alloc_counter.hpp"

namespace visvol::rt {
namespace {

// Busy-waits `ns` (a sleep would hand the CPU back, not model compute).
void spin_ns(std::int64_t ns) {
  const std::int64_t end = monotonic_ns() + ns;
  while (monotonic_ns() < end) {
  }
}

class CountingTask final : public PeriodicTask {
 public:
  void warm_up() override { warmed = true; }
  void tick(const TickTime& t) override {
    if (t.index == 0) {
      allocations_at_start = visvol::testing::thread_allocation_count();
      first_deadline_ns = t.deadline_ns;
    }
    ++ticks;
    last = t;
    if (slow_from >= 0 && t.index >= static_cast<std::uint64_t>(slow_from) &&
        t.index < static_cast<std::uint64_t>(slow_from + slow_ticks)) {
      spin_ns(slow_ns);
    }
    allocations_now = visvol::testing::thread_allocation_count();
  }
  void safe_state() override { ++safe_states; }
  void stopping() override {
    ++stops;
    ticks_at_stop = ticks;
  }

  bool warmed = false;
  std::uint64_t ticks = 0;
  TickTime last;
  std::int64_t first_deadline_ns = 0;
  int slow_from = -1, slow_ticks = 0;
  std::int64_t slow_ns = 0;
  int safe_states = 0;
  int stops = 0;
  std::uint64_t ticks_at_stop = 0;
  std::uint64_t allocations_at_start = 0, allocations_now = 0;
};

LoopConfig test_config() {
  LoopConfig c;
  c.period_ns = 1'000'000;
  c.overrun_limit = 3;
  c.report_ticks = 50;
  c.realtime.priority = 0;  // tests run unprivileged too
  c.realtime.lock_memory = false;
  return c;
}

TEST(PeriodicLoop, RejectsBadConfiguration) {
  CountingTask task;
  PeriodicLoop loop(task);
  LoopConfig c = test_config();
  c.period_ns = 10;
  EXPECT_EQ(loop.start(c).code(), Errc::invalid_argument);
  c = test_config();
  c.overrun_limit = 0;
  EXPECT_EQ(loop.start(c).code(), Errc::invalid_argument);
  c = test_config();
  c.realtime.priority = 120;
  EXPECT_NE(loop.start(c).message().find("priority"), std::string::npos);
  EXPECT_FALSE(loop.running());
}

TEST(PeriodicLoop, TicksAtAbsoluteDeadlinesAndReports) {
  CountingTask task;
  PeriodicLoop loop(task);
  ASSERT_TRUE(loop.start(test_config()).ok());
  EXPECT_TRUE(task.warmed);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const LoopRun run = loop.stop();
  EXPECT_GT(run.totals.ticks, 100u);  // nominally 300; the machine may be loaded
  EXPECT_EQ(run.totals.ticks, task.ticks);
  EXPECT_EQ(run.wake_latency.count(), run.totals.ticks);
  EXPECT_EQ(run.compute.count(), run.totals.ticks);
  // deadlines are whole periods apart: deadline = first + period * (ticks + skipped)
  EXPECT_EQ((task.last.deadline_ns - task.first_deadline_ns) % 1'000'000, 0);
  EXPECT_GE((task.last.deadline_ns - task.first_deadline_ns) / 1'000'000, static_cast<std::int64_t>(task.ticks) - 1);
  EXPECT_GE(task.last.woke_ns, task.last.deadline_ns);
  const LoopReport* report = loop.reports().take();
  ASSERT_NE(report, nullptr);
  EXPECT_EQ(report->wake_latency.count(), 50u);
  EXPECT_GE(report->sequence, 2u);
  EXPECT_EQ(task.allocations_now, task.allocations_at_start) << "the loop allocated while ticking";
  // the task heard of the stop once, after its last tick
  EXPECT_EQ(task.stops, 1);
  EXPECT_EQ(task.ticks_at_stop, task.ticks);
  loop.stop();
  EXPECT_EQ(task.stops, 1) << "a second stop() ran nothing";
}

TEST(PeriodicLoop, OverrunsInARowCallTheSafeStateOnce) {
  CountingTask task;
  task.slow_from = 20;
  task.slow_ticks = 6;  // six ticks of 1.6 ms: each ends after its period
  task.slow_ns = 1'600'000;
  PeriodicLoop loop(task);
  ASSERT_TRUE(loop.start(test_config()).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const LoopRun run = loop.stop();
  EXPECT_GE(run.totals.overruns, 6u);
  EXPECT_GE(run.totals.misses, 3u);  // a 1.6 ms tick runs past the next deadline
  // six in a row with a limit of three: the safe state once per unbroken run
  EXPECT_GE(task.safe_states, 1);
  EXPECT_EQ(static_cast<std::uint64_t>(task.safe_states), run.totals.safe_states);
  EXPECT_GE(run.compute.max_us(), 1600.0);
}

TEST(PeriodicLoop, SkippedDeadlinesAreNotRunLate) {
  CountingTask task;
  task.slow_from = 10;
  task.slow_ticks = 1;
  task.slow_ns = 5'500'000;  // one tick of 5.5 ms: five deadlines pass
  PeriodicLoop loop(task);
  ASSERT_TRUE(loop.start(test_config()).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const LoopRun run = loop.stop();
  EXPECT_GE(run.totals.misses, 5u);
  EXPECT_GE(run.totals.overruns, 1u);
}

}  // namespace
}  // namespace visvol::rt
