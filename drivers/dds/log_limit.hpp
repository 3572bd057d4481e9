// Cyclone DDS's own messages go to stderr through a limiter: each sample a
// misbehaving or hostile peer sends over the size limit is one warning from
// Cyclone ("dropping oversize ... sample N"), and a peer sending them as fast
// as the network allows would fill the console's log. Warnings (and its info
// and configuration lines) pass kBurst at once, then one each kQuietPeriod_s
// (the burst refills at that rate), each line after a gap saying how many
// were left out, and the process says the count left out at exit. Errors
// and fatal messages (a configuration problem, a socket that cannot open)
// always pass. Every line reads "Cyclone DDS: " and Cyclone's text (its own
// header, time and thread, is not in the text it gives a sink). With
// Cyclone's tracing on (<Tracing> in the configuration), its trace output
// carries every line too, unlimited, as the configuration asked.
#pragma once

#include <cstdint>

namespace visvol::dds {

// The rule, apart from Cyclone and the clock: a bucket of `burst` lines that
// refills one line each `quiet_period_s`.
class LogLimiter {
 public:
  LogLimiter(int burst, double quiet_period_s) : burst_(burst), quiet_period_s_(quiet_period_s), tokens_(burst) {}
  // Whether a line at `now_s` (any steady clock, s; not decreasing) is shown;
  // when it is, `left_out` gets the lines left out since the last one shown.
  bool admit(double now_s, std::uint64_t& left_out);
  std::uint64_t pending() const { return left_out_; }  // left out since the last line shown

 private:
  int burst_;
  double quiet_period_s_;
  double tokens_;
  double last_s_ = 0;  // (the bucket starts full: the first line's refill changes nothing)
  std::uint64_t left_out_ = 0;
};

inline constexpr int kLogBurst = 20;
inline constexpr double kQuietPeriod_s = 10.0;

// Routes Cyclone's messages (process-wide: Cyclone has one sink) through a
// LogLimiter(kLogBurst, kQuietPeriod_s) to stderr. Idempotent; Participant
// calls it before it makes a domain.
void install_dds_log_limit();

struct DdsLogCounts {
  std::uint64_t shown = 0;
  std::uint64_t left_out = 0;
};
DdsLogCounts dds_log_counts();

}  // namespace visvol::dds
