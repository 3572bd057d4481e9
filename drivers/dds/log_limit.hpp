// Cyclone DDS's own messages (its warnings and errors: a configuration
// problem, a malformed or oversize sample from a peer) go to stderr through a
// limiter: each sample a misbehaving or hostile peer sends over the size
// limit is one line from Cyclone ("dropping oversize ... sample N"), and a
// peer sending them as fast as the network allows would fill the console's
// log. The first kBurst lines pass ("Cyclone DDS: " and Cyclone's text);
// then at most one each kQuietPeriod_s, with a line saying how many were left
// out before it.
#pragma once

#include <cstdint>

namespace visvol::dds {

// The rule, apart from Cyclone and the clock.
class LogLimiter {
 public:
  LogLimiter(int burst, double quiet_period_s) : burst_(burst), quiet_period_s_(quiet_period_s) {}
  // Whether a line at `now_s` (any steady clock, s) is shown; when it is,
  // `left_out` gets the lines left out since the last one shown.
  bool admit(double now_s, std::uint64_t& left_out);

 private:
  int burst_;
  double quiet_period_s_;
  int shown_ = 0;
  double last_shown_s_ = 0;
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
