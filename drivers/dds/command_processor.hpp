// The command path between DDS and the real-time thread, without DDS:
// rate limiting, decoding and validation, the push into the command queue,
// and the acknowledgement for every command. CommandIntake (command_intake.hpp)
// wraps it with a reader, a writer and a thread; libFuzzer drives it directly.
//
// Thread-safety: one thread (command intake's). Cost: O(constraints + tracked
// sources) per command; a rejection allocates its reason. Not real-time: only
// the queue it pushes into is shared with the real-time thread.
#pragma once

#include <cstdint>
#include <string_view>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "drivers/dds/command_codec.hpp"
#include "msg/samples.hpp"
#include "visvol_msgs.h"

namespace visvol::dds {

// Token buckets: each sender (by its source name) and all senders together
// may send `burst` commands at once and `per_s` per second after that.
// Commands past that are rejected (and acknowledged as such) without being
// decoded.
struct RateLimit {
  double per_source_per_s = 20.0;
  double per_source_burst = 20.0;
  double total_per_s = 100.0;
  double total_burst = 50.0;
};
Status validate(const RateLimit& rate);

class RateLimiter {
 public:
  // Senders tracked at once; past that the one heard from least recently is
  // forgotten (and starts again with a full bucket). The total bucket still
  // bounds a flood from ever-new names.
  static constexpr std::size_t kMaxSources = 32;

  enum class Verdict { pass, source_limited, total_limited };

  explicit RateLimiter(const RateLimit& rate);
  // Whether a command from `source` may pass at `now_s` (any monotonic clock
  // in seconds; an earlier time than the last counts as the last). Takes a
  // token from both buckets when it passes.
  Verdict allow(std::string_view source, double now_s);
  const RateLimit& rate() const { return rate_; }

 private:
  struct Bucket {
    double tokens;
    double last_s;
  };
  struct Source {
    char name[msg::kSourceCapacity];
    Bucket bucket;
    bool used;
  };
  static void refill(Bucket& b, double now_s, double per_s, double burst);
  Source& find_or_add(std::string_view source, double now_s);

  RateLimit rate_;
  Bucket total_;
  Source sources_[kMaxSources] = {};
};

struct CommandCounts {
  std::uint64_t received = 0;
  std::uint64_t accepted = 0;  // pushed into the queue
  std::uint64_t rejected = 0;  // every rejection, including the next two
  std::uint64_t rate_limited = 0;
  std::uint64_t queue_full = 0;
};

class CommandProcessor {
 public:
  // invalid_argument when the limits or the rate are not valid.
  static Result<CommandProcessor> create(const CommandLimits& limits, const RateLimit& rate);

  // Replaces the limits (after a terrain switch); keeps the old ones when the
  // new ones are not valid.
  Status set_limits(const CommandLimits& limits);
  const CommandLimits& limits() const { return limits_; }

  // Handles one received command: rate limit, decode, validate, push. Fills
  // `ack` in every case: accepted (queued), or rejected with the reason.
  void process(const visvol_msgs_msg_dds__Command_& wire, double now_s, msg::CommandQueue& queue, msg::CommandAck& ack);

  const CommandCounts& counts() const { return counts_; }

 private:
  CommandProcessor(const CommandLimits& limits, const RateLimit& rate) : limits_(limits), limiter_(rate) {}
  void reject(msg::CommandAck& ack, std::string_view reason);

  CommandLimits limits_;
  RateLimiter limiter_;
  msg::Command scratch_{};
  CommandCounts counts_;
};

// The source as it may be echoed: printable ASCII ('?' for anything else),
// truncated to fit.
void sanitize_source(const char* source, char (&out)[msg::kSourceCapacity]);

}  // namespace visvol::dds
