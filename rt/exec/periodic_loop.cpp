#include "rt/exec/periodic_loop.hpp"

#include <sched.h>
#include <time.h>

#include <cerrno>

namespace visvol::rt {

Status validate(const LoopConfig& c) {
  if (c.period_ns < 100'000 || c.period_ns > 1'000'000'000) {
    return invalid_argument("loop period: " + std::to_string(c.period_ns) + " ns is outside 100 us .. 1 s");
  }
  if (c.overrun_limit < 1 || c.overrun_limit > 1000) {
    return invalid_argument("overrun limit: " + std::to_string(c.overrun_limit) + " is outside 1..1000");
  }
  if (c.report_ticks < 1) return invalid_argument("report ticks: must be at least 1");
  if (c.settle_ticks > 1'000'000) return invalid_argument("settle ticks: at most 1000000");
  if (c.realtime.priority < 0 || c.realtime.priority > 99) {
    return invalid_argument("real-time priority: " + std::to_string(c.realtime.priority) +
                            " is outside 0..99 (0: no SCHED_FIFO)");
  }
  if (c.realtime.cpu < -1 || c.realtime.cpu >= CPU_SETSIZE) {
    return invalid_argument("cpu: " + std::to_string(c.realtime.cpu) + " is not a CPU number (-1: any)");
  }
  return {};
}

PeriodicLoop::~PeriodicLoop() {
  if (running()) stop();
}

Status PeriodicLoop::start(const LoopConfig& config) {
  if (running()) return Status(Errc::state, "periodic loop: already running");
  VISVOL_RETURN_IF_ERROR(validate(config));
  config_ = config;
  run_ = LoopRun();
  stop_.store(false);
  ready_.store(false);
  thread_ = std::thread([this] { run(); });
  while (!ready_.load(std::memory_order_acquire)) std::this_thread::yield();
  return {};
}

LoopRun PeriodicLoop::stop() {
  if (!running()) return run_;
  stop_.store(true, std::memory_order_release);
  thread_.join();
  return run_;
}

void PeriodicLoop::run() {
  make_current_thread_realtime(config_.realtime, run_.realtime);
  task_.warm_up();
  faults_at_start_ = thread_faults();
  const std::int64_t period = config_.period_ns;
  std::int64_t deadline = monotonic_ns() + period;
  ready_.store(true, std::memory_order_release);
  std::uint64_t index = 0;
  while (!stop_.load(std::memory_order_acquire)) {
    timespec ts{static_cast<time_t>(deadline / 1'000'000'000), static_cast<long>(deadline % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    const std::int64_t woke = monotonic_ns();
    task_.tick({index++, deadline, woke, period});
    const std::int64_t done = monotonic_ns();
    const bool overran = done > deadline + period;
    // deadlines already gone are skipped: the next tick is the next one ahead
    std::int64_t next = deadline + period;
    if (done >= next) {
      const std::int64_t missed = (done - next) / period + 1;
      run_.totals.misses += static_cast<std::uint64_t>(missed);
      next += missed * period;
    }
    end_tick(done - woke, woke - deadline, overran);
    deadline = next;
  }
  task_.stopping();
  if (run_.totals.ticks >= config_.settle_ticks) {
    const ThreadFaults now = thread_faults();
    run_.totals.faults_after_settle = {now.minor - faults_at_start_.minor, now.major - faults_at_start_.major};
  }
}

void PeriodicLoop::end_tick(std::int64_t compute_ns, std::int64_t wake_ns, bool overran) {
  LoopTotals& t = run_.totals;
  ++t.ticks;
  window_wake_.add(wake_ns);
  window_compute_.add(compute_ns);
  run_.wake_latency.add(wake_ns);
  run_.compute.add(compute_ns);
  if (overran) {
    ++t.overruns;
    if (++t.consecutive_overruns == config_.overrun_limit) {
      ++t.safe_states;
      task_.safe_state();
    }
  } else {
    t.consecutive_overruns = 0;
  }
  if (t.ticks == config_.settle_ticks) faults_at_start_ = thread_faults();
  if (t.ticks % config_.report_ticks == 0) {
    if (t.ticks >= config_.settle_ticks) {
      const ThreadFaults now = thread_faults();
      t.faults_after_settle = {now.minor - faults_at_start_.minor, now.major - faults_at_start_.major};
    }
    LoopReport& r = reports_.back();
    r.sequence = ++report_sequence_;
    r.wake_latency = window_wake_;
    r.compute = window_compute_;
    r.totals = t;
    reports_.publish();
    window_wake_.reset();
    window_compute_.reset();
  }
  ticks_.store(t.ticks, std::memory_order_release);
}

}  // namespace visvol::rt
