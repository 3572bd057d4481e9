#include "drivers/dds/log_limit.hpp"

#include <dds/dds.h>
#include <stdio.h>  // flockfile

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace visvol::dds {

bool LogLimiter::admit(double now_s, std::uint64_t& left_out) {
  left_out = 0;
  if (quiet_period_s_ > 0) {
    tokens_ = std::min(static_cast<double>(burst_), tokens_ + std::max(0.0, now_s - last_s_) / quiet_period_s_);
  }
  last_s_ = now_s;
  if (tokens_ < 1.0) {
    ++left_out_;
    return false;
  }
  tokens_ -= 1.0;
  left_out = left_out_;
  left_out_ = 0;
  return true;
}

namespace {

struct Sink {
  std::mutex mutex;  // Cyclone calls from any of its threads (never visvol's 1 kHz one)
  LogLimiter limiter{kLogBurst, kQuietPeriod_s};
  DdsLogCounts counts;
};

// Trivially destructible but for the mutex, which glibc does not tear down:
// Cyclone's threads may still log while the process exits.
Sink& sink() {
  static Sink s;
  return s;
}

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

void say_left_out(std::uint64_t left_out) {
  std::fprintf(stderr, "Cyclone DDS: %llu more warnings were left out (%d at once, then one each %.0f s)\n",
               static_cast<unsigned long long>(left_out), kLogBurst, kQuietPeriod_s);
}

extern "C" void limited_log(void* arg, const dds_log_data_t* data) {
  Sink& s = *static_cast<Sink*>(arg);
  std::lock_guard<std::mutex> lock(s.mutex);
  std::uint64_t left_out = 0;
  // errors and fatal messages always: Cyclone aborts after a fatal one
  const bool always = (data->priority & (DDS_LC_FATAL | DDS_LC_ERROR)) != 0;
  if (!always && !s.limiter.admit(now_s(), left_out)) {
    ++s.counts.left_out;
    return;
  }
  ++s.counts.shown;
  flockfile(stderr);  // one line, whoever else writes to stderr
  if (left_out > 0) say_left_out(left_out);
  std::fputs("Cyclone DDS: ", stderr);
  std::fwrite(data->message, 1, data->size, stderr);
  if (data->size == 0 || data->message[data->size - 1] != '\n') std::fputc('\n', stderr);
  std::fflush(stderr);
  funlockfile(stderr);
}

// At exit: the warnings left out since the last line shown.
extern "C" void say_pending() {
  Sink& s = sink();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.limiter.pending() > 0) say_left_out(s.limiter.pending());
}

}  // namespace

void install_dds_log_limit() {
  static std::once_flag once;
  std::call_once(once, [] {
    dds_set_log_sink(limited_log, &sink());
    std::atexit(say_pending);
  });
}

DdsLogCounts dds_log_counts() {
  Sink& s = sink();
  std::lock_guard<std::mutex> lock(s.mutex);
  return s.counts;
}

}  // namespace visvol::dds
