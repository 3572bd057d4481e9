#include "app/fault_injection.hpp"

#include <cerrno>
#include <cmath>
#include <ctime>

namespace visvol::app {

StallingTask::StallingTask(rt::PeriodicTask& task, double at_s, double for_s)
    : task_(task), at_ns_(std::llround(at_s * 1e9)), for_ns_(std::llround(for_s * 1e9)) {}

void StallingTask::tick(const rt::TickTime& time) {
  if (first_ns_ < 0) first_ns_ = time.deadline_ns;
  if (!stalled_ && time.deadline_ns - first_ns_ >= at_ns_) {
    stalled_ = true;
    const std::int64_t until_ns = time.woke_ns + for_ns_;
    timespec until{static_cast<std::time_t>(until_ns / 1'000'000'000), static_cast<long>(until_ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr) == EINTR) {
    }
  }
  task_.tick(time);
}

}  // namespace visvol::app
