// Rate limiting and the command path to the queue, without DDS, on a clock
// the test drives.
#include "drivers/dds/command_processor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace visvol::dds {
namespace {

using Verdict = RateLimiter::Verdict;

RateLimit rate(double per_s, double burst, double total_per_s = 1000.0, double total_burst = 1000.0) {
  return RateLimit{per_s, burst, total_per_s, total_burst};
}

TEST(RateLimiter, BurstThenSustainedRate) {
  RateLimiter r(rate(2.0, 3.0));
  const double t = 100.0;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r.allow("a", t), Verdict::pass);
  EXPECT_EQ(r.allow("a", t), Verdict::source_limited);
  EXPECT_EQ(r.allow("a", t + 0.4), Verdict::source_limited);  // 0.8 tokens
  EXPECT_EQ(r.allow("a", t + 0.5), Verdict::pass);            // 1 token
  EXPECT_EQ(r.allow("a", t + 0.5), Verdict::source_limited);
  // a long pause refills to the burst, not beyond
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r.allow("a", t + 60.0), Verdict::pass);
  EXPECT_EQ(r.allow("a", t + 60.0), Verdict::source_limited);
  // time going backwards does not mint tokens
  EXPECT_EQ(r.allow("a", t), Verdict::source_limited);
}

TEST(RateLimiter, SourcesHaveTheirOwnBucketsAndShareTheTotal) {
  RateLimiter r(rate(1.0, 2.0, 1.0, 5.0));
  EXPECT_EQ(r.allow("a", 0.0), Verdict::pass);
  EXPECT_EQ(r.allow("a", 0.0), Verdict::pass);
  EXPECT_EQ(r.allow("a", 0.0), Verdict::source_limited);
  EXPECT_EQ(r.allow("b", 0.0), Verdict::pass);  // b is not held back by a
  EXPECT_EQ(r.allow("b", 0.0), Verdict::pass);
  EXPECT_EQ(r.allow("c", 0.0), Verdict::pass);
  EXPECT_EQ(r.allow("d", 0.0), Verdict::total_limited);  // 5 in all
}

TEST(RateLimiter, ForgetsTheLeastRecentSourceWhenFull) {
  RateLimiter r(rate(1.0, 1.0));
  EXPECT_EQ(r.allow("first", 0.0), Verdict::pass);
  EXPECT_EQ(r.allow("first", 0.0), Verdict::source_limited);
  for (std::size_t i = 0; i < RateLimiter::kMaxSources - 1; ++i) {
    EXPECT_EQ(r.allow("s" + std::to_string(i), 0.1), Verdict::pass);
  }
  // still tracked: limited
  EXPECT_EQ(r.allow("first", 0.2), Verdict::source_limited);
  // one more name evicts the least recently seen: s0 (0.1), not first (0.2)
  EXPECT_EQ(r.allow("newcomer", 0.3), Verdict::pass);
  EXPECT_EQ(r.allow("s0", 0.3), Verdict::pass);  // forgotten, so a fresh bucket
}

TEST(RateLimit, Validation) {
  EXPECT_TRUE(validate(RateLimit{}).ok());
  EXPECT_FALSE(validate(rate(0.0, 1.0)).ok());
  EXPECT_FALSE(validate(rate(1.0, 0.5)).ok());
  EXPECT_FALSE(validate(rate(1.0, 1.0, std::nan(""), 1.0)).ok());
}

CommandLimits limits() {
  CommandLimits l;
  l.min = {0.0, 0.0, 0.0};
  l.max = {100.0, 100.0, 100.0};
  return l;
}

struct Raw {
  visvol_msgs_msg_dds__Command_ m{};
  char source[16] = "op";
  char pack[4] = "";
  explicit Raw(msg::CommandKind kind, std::uint64_t seq) {
    m.kind = static_cast<std::uint8_t>(kind);
    m.sequence_number = seq;
    m.source = source;
    m.pack_id = pack;
  }
};

TEST(CommandProcessor, AcknowledgesEveryCommand) {
  Result<CommandProcessor> p = CommandProcessor::create(limits(), RateLimit{});
  ASSERT_TRUE(p.ok());
  msg::CommandQueue queue;
  msg::CommandAck ack{};

  Raw good(msg::CommandKind::start, 1);
  p->process(good.m, 0.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::accepted);
  EXPECT_EQ(ack.sequence, 1u);
  EXPECT_EQ(msg::text_of(ack.source), "op");
  EXPECT_STREQ(ack.reason, "");

  Raw bad(msg::CommandKind::set_segment_count, 2);
  bad.m.segment_count = 0;
  p->process(bad.m, 0.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::rejected);
  EXPECT_EQ(ack.sequence, 2u);
  EXPECT_EQ(ack.kind, static_cast<std::uint8_t>(msg::CommandKind::set_segment_count));
  EXPECT_EQ(std::string(ack.reason).rfind("segment_count: 0 is outside", 0), 0u) << ack.reason;

  Raw unknown(msg::CommandKind::start, 3);
  unknown.m.kind = 200;
  unknown.m.source = nullptr;  // never from Cyclone, but must not crash
  p->process(unknown.m, 0.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::rejected);
  EXPECT_EQ(ack.kind, 200);
  EXPECT_STREQ(ack.source, "");

  EXPECT_EQ(queue.size_approx(), 1u);
  const CommandCounts& c = p->counts();
  EXPECT_EQ(c.received, 3u);
  EXPECT_EQ(c.accepted, 1u);
  EXPECT_EQ(c.rejected, 2u);
}

TEST(CommandProcessor, RateLimitedBeforeDecoding) {
  Result<CommandProcessor> p = CommandProcessor::create(limits(), rate(1.0, 2.0));
  ASSERT_TRUE(p.ok());
  msg::CommandQueue queue;
  msg::CommandAck ack{};
  Raw garbage(msg::CommandKind::start, 1);
  garbage.m.kind = 99;
  p->process(garbage.m, 5.0, queue, ack);  // a token spent on garbage
  p->process(garbage.m, 5.0, queue, ack);
  EXPECT_NE(std::string(ack.reason).find("kind: 99"), std::string::npos);
  Raw good(msg::CommandKind::start, 2);
  p->process(good.m, 5.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::rejected);
  EXPECT_STREQ(ack.reason, "rate limit: this source sent more than 2 commands at once or 1 per second");
  EXPECT_EQ(p->counts().rate_limited, 1u);
  p->process(good.m, 6.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::accepted);
}

TEST(CommandProcessor, FullQueueIsARejection) {
  Result<CommandProcessor> p = CommandProcessor::create(limits(), rate(1e6, 1e6));
  ASSERT_TRUE(p.ok());
  msg::CommandQueue queue;
  msg::CommandAck ack{};
  Raw good(msg::CommandKind::stop, 1);
  for (std::size_t i = 0; i < msg::CommandQueue::capacity(); ++i) {
    p->process(good.m, 0.0, queue, ack);
    ASSERT_EQ(ack.result, msg::AckResult::accepted);
  }
  p->process(good.m, 0.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::rejected);
  EXPECT_STREQ(ack.reason, "command queue full: the planner is not taking commands");
  EXPECT_EQ(p->counts().queue_full, 1u);
  msg::Command c{};
  ASSERT_TRUE(queue.try_pop(c));
  p->process(good.m, 0.0, queue, ack);
  EXPECT_EQ(ack.result, msg::AckResult::accepted);
}

TEST(CommandProcessor, SourceIsSanitizedForTheAck) {
  Result<CommandProcessor> p = CommandProcessor::create(limits(), RateLimit{});
  ASSERT_TRUE(p.ok());
  msg::CommandQueue queue;
  msg::CommandAck ack{};
  Raw r(msg::CommandKind::start, 1);
  char weird[] = "a\nb\x7f";
  r.m.source = weird;
  p->process(r.m, 0.0, queue, ack);
  EXPECT_STREQ(ack.source, "a?b?");
  EXPECT_EQ(ack.result, msg::AckResult::rejected);
  std::string longer(200, 'x');
  r.m.source = longer.data();
  p->process(r.m, 0.0, queue, ack);
  EXPECT_EQ(msg::text_of(ack.source).size(), msg::kSourceCapacity - 1);
}

TEST(CommandProcessor, InvalidConfigurationIsRefused) {
  CommandLimits l = limits();
  l.max.x_m = -1.0;
  Result<CommandProcessor> p = CommandProcessor::create(l, RateLimit{});
  ASSERT_FALSE(p.ok());
  Result<CommandProcessor> q = CommandProcessor::create(limits(), RateLimit{});
  ASSERT_TRUE(q.ok());
  EXPECT_FALSE(q->set_limits(l).ok());
  EXPECT_EQ(q->limits().max.x_m, 100.0);  // kept the old ones
}

}  // namespace
}  // namespace visvol::dds
