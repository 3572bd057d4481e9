#include "drivers/dds/log_limit.hpp"

#include <dds/dds.h>

#include <chrono>
#include <cstdio>
#include <mutex>

namespace visvol::dds {

bool LogLimiter::admit(double now_s, std::uint64_t& left_out) {
  left_out = 0;
  if (shown_ < burst_ || now_s - last_shown_s_ >= quiet_period_s_) {
    if (shown_ < burst_) ++shown_;
    last_shown_s_ = now_s;
    left_out = left_out_;
    left_out_ = 0;
    return true;
  }
  ++left_out_;
  return false;
}

namespace {

struct Sink {
  std::mutex mutex;  // Cyclone calls from any of its threads (never visvol's 1 kHz one)
  LogLimiter limiter{kLogBurst, kQuietPeriod_s};
  DdsLogCounts counts;
};

Sink& sink() {
  static Sink s;  // never destroyed before Cyclone's last message: a function-local static outlives the domains
  return s;
}

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

extern "C" void limited_log(void* arg, const dds_log_data_t* data) {
  Sink& s = *static_cast<Sink*>(arg);
  std::lock_guard<std::mutex> lock(s.mutex);
  std::uint64_t left_out = 0;
  if (!s.limiter.admit(now_s(), left_out)) {
    ++s.counts.left_out;
    return;
  }
  ++s.counts.shown;
  if (left_out > 0) {
    std::fprintf(stderr, "visvol: %llu more lines from Cyclone DDS were left out (at most one each %.0f s after %d)\n",
                 static_cast<unsigned long long>(left_out), kQuietPeriod_s, kLogBurst);
  }
  std::fputs("Cyclone DDS: ", stderr);  // (its own header, time and thread, is not in the message)
  std::fwrite(data->message, 1, data->size, stderr);
  if (data->size == 0 || data->message[data->size - 1] != '\n') std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace

void install_dds_log_limit() {
  static std::once_flag once;
  std::call_once(once, [] { dds_set_log_sink(limited_log, &sink()); });
}

DdsLogCounts dds_log_counts() {
  Sink& s = sink();
  std::lock_guard<std::mutex> lock(s.mutex);
  return s.counts;
}

}  // namespace visvol::dds
