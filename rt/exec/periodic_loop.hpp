// The periodic real-time thread: wakes at absolute deadlines on
// CLOCK_MONOTONIC (clock_nanosleep, TIMER_ABSTIME: no drift), runs one tick of
// its task, and measures itself.
//
//   wake-up latency  actual wake-up minus the scheduled deadline
//   compute time     tick start to tick end
//   overrun          a tick that ended after its period was over
//   miss             a deadline that had already passed when the previous
//                    tick ended: it is skipped, not run late (the next tick
//                    runs at the next deadline still ahead)
//
// After `overrun_limit` overruns in a row the task's safe_state() is called
// (on the loop thread) once; it is called again only after a tick that did
// not overrun has broken the run.
//
// Health: every `report_ticks` ticks the loop hands a LoopReport (histograms
// of that window and totals) to reports() (a LatestValue: the reader takes
// the newest, the loop never waits). The whole run's histograms are kept too
// and returned by stop().
//
// Ownership: the task is borrowed and must outlive the loop. Thread-safety:
// start()/stop() from one controlling thread; reports() from one reader
// thread. Cost: a thread; start() allocates it, nothing after.
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "rt/exec/histogram.hpp"
#include "rt/exec/realtime.hpp"

namespace visvol::rt {

struct TickTime {
  std::uint64_t index = 0;       // 0, 1, 2, ...: ticks run (skipped deadlines not counted)
  std::int64_t deadline_ns = 0;  // when the tick was due (CLOCK_MONOTONIC)
  std::int64_t woke_ns = 0;      // when the thread woke
  std::int64_t period_ns = 0;
};

class PeriodicTask {
 public:
  virtual ~PeriodicTask() = default;
  // Called once on the loop thread before the first tick (after the thread was
  // made real-time): touch what the ticks will touch.
  virtual void warm_up() {}
  // One tick. Real-time: no allocation, locks, logging or blocking I/O.
  virtual void tick(const TickTime& time) = 0;
  // `overrun_limit` overruns in a row: go to the safe state.
  virtual void safe_state() = 0;
  // Once on the loop thread after the last tick, when stop() was asked (a
  // supervisor's SIGTERM, Ctrl-C, the end of a session): leave the hardware
  // safe (for the executive: zero force, disabled). Real-time rules apply.
  virtual void stopping() {}
};

struct LoopConfig {
  std::int64_t period_ns = 1'000'000;  // 1 kHz
  int overrun_limit = 3;               // consecutive overruns before safe_state()
  std::uint32_t report_ticks = 100;    // a LoopReport every this many ticks
  // Page faults are counted from this tick on: the first ticks run code and
  // touch data for the first time (cold pages, even when locked on fault).
  std::uint32_t settle_ticks = 100;
  RealtimeConfig realtime;
};
Status validate(const LoopConfig& config);

struct LoopTotals {
  std::uint64_t ticks = 0;
  std::uint64_t overruns = 0;
  std::uint64_t misses = 0;       // deadlines skipped
  std::uint64_t safe_states = 0;  // safe_state() calls
  int consecutive_overruns = 0;
  ThreadFaults faults_after_settle;  // of the loop thread, from tick settle_ticks on
};

struct LoopReport {
  std::uint64_t sequence = 0;
  DurationHistogram wake_latency;  // this window
  DurationHistogram compute;       // this window
  LoopTotals totals;
};

struct LoopRun {
  DurationHistogram wake_latency;  // the whole run
  DurationHistogram compute;
  LoopTotals totals;
  RealtimeReport realtime;  // what the thread got
};

class PeriodicLoop {
 public:
  explicit PeriodicLoop(PeriodicTask& task) : task_(task) {}
  ~PeriodicLoop();
  PeriodicLoop(const PeriodicLoop&) = delete;
  PeriodicLoop& operator=(const PeriodicLoop&) = delete;

  // Validates the configuration and starts the thread; returns once the task
  // has warmed up and the first deadline is set.
  Status start(const LoopConfig& config);
  // Stops after the current tick and returns the whole run.
  LoopRun stop();
  bool running() const { return thread_.joinable(); }

  LatestValue<LoopReport>& reports() { return reports_; }
  // Ticks completed so far (any thread).
  std::uint64_t ticks() const { return ticks_.load(std::memory_order_acquire); }

 private:
  void run();
  void end_tick(std::int64_t compute_ns, std::int64_t wake_ns, bool overran);

  PeriodicTask& task_;
  LoopConfig config_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> ready_{false};
  std::atomic<std::uint64_t> ticks_{0};
  LatestValue<LoopReport> reports_;
  // loop thread only, until joined
  LoopRun run_;
  DurationHistogram window_wake_, window_compute_;
  std::uint64_t report_sequence_ = 0;
  ThreadFaults faults_at_start_;
};

}  // namespace visvol::rt
