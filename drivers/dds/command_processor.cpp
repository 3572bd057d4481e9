#include "drivers/dds/command_processor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace visvol::dds {

void sanitize_source(const char* source, char (&out)[msg::kSourceCapacity]) {
  std::size_t n = 0;
  if (source) {
    for (; n + 1 < msg::kSourceCapacity && source[n] != '\0'; ++n) {
      const char c = source[n];
      out[n] = (c >= 0x20 && c <= 0x7e) ? c : '?';
    }
  }
  out[n] = '\0';
}

Status validate(const RateLimit& r) {
  const double values[4] = {r.per_source_per_s, r.per_source_burst, r.total_per_s, r.total_burst};
  for (const double v : values) {
    if (!std::isfinite(v) || v <= 0.0) {
      return invalid_argument("command rate limit: every rate and burst must be finite and > 0");
    }
  }
  if (r.per_source_burst < 1.0 || r.total_burst < 1.0) {
    return invalid_argument("command rate limit: a burst below 1 would refuse every command");
  }
  return Status();
}

// Rate limiter ---------------------------------------------------------------

RateLimiter::RateLimiter(const RateLimit& rate) : rate_(rate), total_{rate.total_burst, 0.0} {}

void RateLimiter::refill(Bucket& b, double now_s, double per_s, double burst) {
  if (now_s > b.last_s) {
    b.tokens = std::min(burst, b.tokens + (now_s - b.last_s) * per_s);
    b.last_s = now_s;
  }
}

RateLimiter::Source& RateLimiter::find_or_add(std::string_view source, double now_s) {
  Source* oldest = &sources_[0];
  for (Source& s : sources_) {
    if (s.used && msg::text_of(s.name) == source) return s;
    if (!s.used) {
      oldest = &s;
      break;
    }
    if (s.bucket.last_s < oldest->bucket.last_s) oldest = &s;
  }
  msg::copy_text(oldest->name, source);
  oldest->bucket = Bucket{rate_.per_source_burst, now_s};
  oldest->used = true;
  return *oldest;
}

RateLimiter::Verdict RateLimiter::allow(std::string_view source, double now_s) {
  refill(total_, now_s, rate_.total_per_s, rate_.total_burst);
  Source& s = find_or_add(source, now_s);
  refill(s.bucket, now_s, rate_.per_source_per_s, rate_.per_source_burst);
  if (s.bucket.tokens < 1.0) return Verdict::source_limited;
  if (total_.tokens < 1.0) return Verdict::total_limited;
  s.bucket.tokens -= 1.0;
  total_.tokens -= 1.0;
  return Verdict::pass;
}

// Processor ------------------------------------------------------------------

Result<CommandProcessor> CommandProcessor::create(const CommandLimits& limits, const RateLimit& rate) {
  VISVOL_RETURN_IF_ERROR(validate_limits(limits));
  VISVOL_RETURN_IF_ERROR(validate(rate));
  return CommandProcessor(limits, rate);
}

Status CommandProcessor::set_limits(const CommandLimits& limits) {
  VISVOL_RETURN_IF_ERROR(validate_limits(limits));
  limits_ = limits;
  return Status();
}

void CommandProcessor::reject(msg::CommandAck& ack, std::string_view reason) {
  ++counts_.rejected;
  ack.result = msg::AckResult::rejected;
  msg::copy_text(ack.reason, reason);
}

void CommandProcessor::process(const visvol_msgs_msg_dds__Command_& wire, double now_s, msg::CommandQueue& queue,
                               msg::CommandAck& ack) {
  ++counts_.received;
  ack = msg::CommandAck{};
  sanitize_source(wire.source, ack.source);
  ack.sequence = wire.sequence_number;
  ack.kind = wire.kind;

  // rate limit first: a flood costs no decoding
  const RateLimiter::Verdict verdict = limiter_.allow(msg::text_of(ack.source), now_s);
  if (verdict != RateLimiter::Verdict::pass) {
    ++counts_.rate_limited;
    const RateLimit& r = limiter_.rate();
    const bool per_source = verdict == RateLimiter::Verdict::source_limited;
    char reason[msg::kReasonCapacity];
    std::snprintf(reason, sizeof reason, "rate limit: %s sent more than %.0f commands at once or %.0f per second",
                  per_source ? "this source" : "all sources together", per_source ? r.per_source_burst : r.total_burst,
                  per_source ? r.per_source_per_s : r.total_per_s);
    reject(ack, reason);
    return;
  }

  // decode and validate in full
  const Status status = decode_and_validate(wire, limits_, scratch_);
  if (!status.ok()) {
    reject(ack, status.message());
    return;
  }

  // hand over to the real-time thread; a full queue means it is not taking any
  if (!queue.try_push(scratch_)) {
    ++counts_.queue_full;
    reject(ack, "command queue full: the planner is not taking commands");
    return;
  }
  ++counts_.accepted;
  ack.result = msg::AckResult::accepted;
}

}  // namespace visvol::dds
