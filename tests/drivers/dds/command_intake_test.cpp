// Command intake with real Cyclone participants in this process (domain 214,
// loopback): a sender writes Command_ samples, intake validates, queues and
// acknowledges them.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "drivers/dds/command_intake.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::loopback;
using test::make_participant;
using test::wait_until;
constexpr std::uint32_t kDomain = test::kDomainCommandIntake;

CommandLimits sf_limits() {
  CommandLimits l;
  l.min = {540000.0, 4180000.0, -10.0};
  l.max = {551100.0, 4194000.0, 900.0};
  l.max_segments = 128;
  l.max_constraints = 4;
  EXPECT_TRUE(add_known_pack(l, "sf_north").ok());
  EXPECT_TRUE(add_known_pack(l, "taunus").ok());
  return l;
}

// The sending side: what visvol-echo and other systems do.
class Sender {
 public:
  explicit Sender(const Participant& p)
      : writer_(Writer::create(p, Topic::command)), acks_(Reader::create(p, Topic::command_ack)) {
    EXPECT_TRUE(writer_.ok() && acks_.ok());
  }
  bool ready(double timeout_s) {
    return writer_->wait_for_readers(1, timeout_s).ok() && acks_->wait_for_writers(1, timeout_s).ok();
  }
  void send(const visvol_msgs_msg_dds__Command_& msg) { ASSERT_EQ(writer_->write(&msg), 0); }
  dds_return_t write(const visvol_msgs_msg_dds__Command_& msg) { return writer_->write(&msg); }
  void send(msg::Command c) {
    CommandMessage m;
    send(m.fill(c));
  }
  // Collects acknowledgements until `count` have arrived or the time passes.
  std::map<std::uint64_t, msg::CommandAck> acks(std::size_t count, double timeout_s) {
    wait_until(
        [&] {
          (void)acks_->take<visvol_msgs_msg_dds__CommandAck_>(
              [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
                received_[m.sequence_number] = decode_ack(m);
              },
              64);
          return received_.size() >= count;
        },
        timeout_s);
    return received_;
  }

 private:
  Result<Writer> writer_;
  Result<Reader> acks_;
  std::map<std::uint64_t, msg::CommandAck> received_;
};

msg::Command base(msg::CommandKind kind, std::uint64_t seq, const char* source = "test-operator") {
  msg::Command c{};
  c.kind = kind;
  c.sequence = seq;
  msg::copy_text(c.source, source);
  return c;
}

struct Fixture {
  std::unique_ptr<Participant> console;
  std::unique_ptr<Participant> operator_side;
  msg::CommandQueue queue;
  msg::AckQueue executive_acks;
  std::unique_ptr<CommandIntake> intake;

  explicit Fixture(const IntakeConfig& config) {
    console = make_participant(loopback(kDomain));
    operator_side = make_participant(loopback(kDomain));
    if (!console || !operator_side) return;
    Result<std::unique_ptr<CommandIntake>> r = CommandIntake::start(*console, config, queue, &executive_acks);
    EXPECT_TRUE(r.ok()) << r.status().message();
    if (r.ok()) intake = std::move(*r);
  }
};

IntakeConfig default_config() {
  IntakeConfig c;
  c.limits = sf_limits();
  return c;
}

TEST(CommandIntake, ValidCommandIsQueuedAndAccepted) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));

  msg::Command c = base(msg::CommandKind::set_endpoints, 1);
  c.endpoints = {{541000.0, 4181000.0, 120.0}, {550000.0, 4190000.0, 80.0}};
  sender.send(c);
  msg::Command o = base(msg::CommandKind::set_objective, 2);
  o.objective = msg::Objective::show;
  sender.send(o);

  const auto acks = sender.acks(2, 5.0);
  ASSERT_EQ(acks.size(), 2u);
  for (const auto& [seq, ack] : acks) {
    EXPECT_EQ(ack.result, msg::AckResult::accepted) << seq << ": " << ack.reason;
    EXPECT_EQ(msg::text_of(ack.source), "test-operator");
    EXPECT_STREQ(ack.reason, "");
  }
  EXPECT_EQ(acks.at(1).kind, static_cast<std::uint8_t>(msg::CommandKind::set_endpoints));

  msg::Command got{};
  ASSERT_TRUE(f.queue.try_pop(got));
  EXPECT_EQ(got.kind, msg::CommandKind::set_endpoints);
  EXPECT_EQ(got.sequence, 1u);
  EXPECT_EQ(got.endpoints.end.x_m, 550000.0);
  ASSERT_TRUE(f.queue.try_pop(got));
  EXPECT_EQ(got.kind, msg::CommandKind::set_objective);
  EXPECT_EQ(got.objective, msg::Objective::show);
  EXPECT_FALSE(f.queue.try_pop(got));
}

// Discovery is not symmetric: a sender may see the intake's ack writer
// before that writer sees the sender's reader. An answer written in between
// must still reach it.
TEST(CommandIntake, AcksWrittenBeforeTheSendersReaderMatchedStillArrive) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Result<Writer> writer = Writer::create(*f.operator_side, Topic::command);
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE(writer->wait_for_readers(1, 5.0).ok());
  // several answers, not one: a late joiner must get every stored ack, not
  // only the newest (Cyclone keeps one unless the durability service says more)
  CommandMessage m;
  for (std::uint64_t seq = 41; seq <= 43; ++seq) {
    msg::Command o = base(msg::CommandKind::set_objective, seq);
    o.objective = msg::Objective::show;
    ASSERT_EQ(writer->write(&m.fill(o)), 0);
  }
  int popped = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        msg::Command got{};
        while (f.queue.try_pop(got)) ++popped;
        return popped == 3;
      },
      5.0));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the acks are out, to nobody

  Result<Reader> acks = Reader::create(*f.operator_side, Topic::command_ack);
  ASSERT_TRUE(acks.ok());
  ASSERT_TRUE(acks->wait_for_writers(1, 5.0).ok());
  std::set<std::uint64_t> accepted;
  ASSERT_TRUE(wait_until(
      [&] {
        (void)acks->take<visvol_msgs_msg_dds__CommandAck_>(
            [&](const visvol_msgs_msg_dds__CommandAck_& a, const dds_sample_info_t&) {
              const msg::CommandAck ack = decode_ack(a);
              if (ack.result == msg::AckResult::accepted) accepted.insert(ack.sequence);
            },
            8);
        return accepted.size() == 3;
      },
      5.0))
      << accepted.size() << " of 3 acks arrived";
  EXPECT_EQ(accepted, (std::set<std::uint64_t>{41, 42, 43}));
}

TEST(CommandIntake, BadCommandsAreRejectedWithReasonsAndIntakeGoesOn) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  const double nan = std::numeric_limits<double>::quiet_NaN();

  std::map<std::uint64_t, std::string> expect;  // sequence -> part of the reason
  msg::Command c = base(msg::CommandKind::set_endpoints, 10);
  c.endpoints = {{nan, 4181000.0, 100.0}, {550000.0, 4190000.0, 80.0}};
  sender.send(c);
  expect[10] = "start_m.x: nan is not a finite number";
  c = base(msg::CommandKind::set_endpoints, 11);
  c.endpoints = {{541000.0, 4181000.0, 100.0}, {560000.0, 4190000.0, 80.0}};
  sender.send(c);
  expect[11] = "end_m.x: 560000 m is outside the pack's x range [540000, 551100] m";
  c = base(msg::CommandKind::set_segment_count, 12);
  c.segment_count = 100000;
  sender.send(c);
  expect[12] = "segment_count: 100000 is outside the 2..128 segments reserved";
  c = base(msg::CommandKind::set_weights, 13);
  c.weights = {1.0, -2.0, 0.0, 0.0};
  sender.send(c);
  expect[13] = "k2_terrain: -2 is outside [0, 1000000]";
  c = base(msg::CommandKind::switch_terrain, 14);
  msg::copy_text(c.pack_id, "alps");
  sender.send(c);
  expect[14] = "pack_id: 'alps' is not a pack on this console";
  c = base(msg::CommandKind::set_constraints, 15);
  c.constraints.count = 5;
  for (msg::Constraint& k : c.constraints.items) k = {msg::ConstraintKind::clearance, {}, 50.0};
  sender.send(c);
  expect[15] = "constraints: 5 given, at most 4 reserved";

  // hand-made messages: values a Command cannot even hold
  CommandMessage m;
  visvol_msgs_msg_dds__Command_ raw = m.fill(base(msg::CommandKind::start, 16));
  raw.kind = 77;
  sender.send(raw);
  expect[16] = "kind: 77 is not a known command (1..11)";
  raw = m.fill(base(msg::CommandKind::set_objective, 17));
  raw.objective = 9;
  sender.send(raw);
  expect[17] = "objective: 9 is not known (1 hide, 2 show)";
  raw = m.fill(base(msg::CommandKind::start, 18));
  char bad_source[] = "op\x01rator";
  raw.source = bad_source;
  sender.send(raw);
  expect[18] = "source: holds characters outside printable ASCII";
  std::vector<visvol_msgs_msg_dds__Constraint_> many(msg::kMaxConstraints + 1);  // one more than fit
  raw = m.fill(base(msg::CommandKind::set_constraints, 19));
  raw.constraints._buffer = many.data();
  raw.constraints._length = static_cast<std::uint32_t>(many.size());
  raw.constraints._maximum = static_cast<std::uint32_t>(many.size());
  sender.send(raw);
  expect[19] = "constraints: 516 given, at most 515 fit";

  // and a good one after all that
  sender.send(base(msg::CommandKind::start, 20));

  const auto acks = sender.acks(expect.size() + 1, 5.0);
  ASSERT_EQ(acks.size(), expect.size() + 1);
  for (const auto& [seq, part] : expect) {
    const msg::CommandAck& ack = acks.at(seq);
    EXPECT_EQ(ack.result, msg::AckResult::rejected) << seq;
    EXPECT_NE(std::string(ack.reason).find(part), std::string::npos)
        << seq << ": '" << ack.reason << "' lacks '" << part << "'";
  }
  EXPECT_EQ(msg::text_of(acks.at(18).source), "op?rator");
  EXPECT_EQ(acks.at(16).kind, 77);
  EXPECT_EQ(acks.at(20).result, msg::AckResult::accepted) << acks.at(20).reason;

  msg::Command got{};
  ASSERT_TRUE(f.queue.try_pop(got));
  EXPECT_EQ(got.kind, msg::CommandKind::start);
  EXPECT_FALSE(f.queue.try_pop(got));  // nothing rejected reached the planner
  const IntakeStats s = f.intake->stats();
  EXPECT_EQ(s.commands.received, expect.size() + 1);
  EXPECT_EQ(s.commands.accepted, 1u);
  EXPECT_EQ(s.commands.rejected, expect.size());
  EXPECT_EQ(s.ack_errors, 0u);
}

// A sample larger than kMaxSampleBytes is dropped by Cyclone before it is
// reassembled or decoded (25 million observers in one command took a console
// to 950 MiB of locked memory): the intake never sees it, and goes on.
TEST(CommandIntake, ASampleOverTheSizeLimitNeverArrives) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  CommandMessage m;
  std::vector<visvol_msgs_msg_dds__Constraint_> huge(kMaxSampleBytes / 32);  // 40 bytes each serialised
  visvol_msgs_msg_dds__Command_ raw = m.fill(base(msg::CommandKind::set_constraints, 30));
  raw.constraints._buffer = huge.data();
  raw.constraints._length = static_cast<std::uint32_t>(huge.size());
  raw.constraints._maximum = static_cast<std::uint32_t>(huge.size());
  (void)sender.write(raw);  // the writer's side has the limit too: refused or dropped
  sender.send(base(msg::CommandKind::start, 31));
  const auto acks = sender.acks(2, 3.0);
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks.begin()->first, 31u);
  EXPECT_EQ(f.intake->stats().commands.received, 1u);
}

TEST(CommandIntake, FloodIsRateLimitedAndEveryCommandAcknowledged) {
  IntakeConfig config = default_config();
  config.rate.per_source_burst = 10.0;
  config.rate.per_source_per_s = 5.0;
  Fixture f(config);
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));

  constexpr std::uint64_t kFlood = 400;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint64_t seq = 1; seq <= kFlood; ++seq) sender.send(base(msg::CommandKind::start, seq));
  const auto acks = sender.acks(kFlood, 20.0);
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(acks.size(), kFlood);

  std::size_t accepted = 0, limited = 0;
  for (const auto& [seq, ack] : acks) {
    if (ack.result == msg::AckResult::accepted) {
      ++accepted;
    } else {
      EXPECT_NE(std::string(ack.reason).find("rate limit: this source sent more than 10"), std::string::npos)
          << ack.reason;
      ++limited;
    }
  }
  // the burst plus what the rate refilled meanwhile
  EXPECT_GE(accepted, 10u);
  EXPECT_LE(static_cast<double>(accepted), 10.0 + 5.0 * elapsed_s + 1.0);
  EXPECT_EQ(accepted + limited, kFlood);
  EXPECT_EQ(f.intake->stats().commands.rate_limited, limited);

  // another sender is not starved by the flood
  msg::Command other = base(msg::CommandKind::stop, kFlood + 1, "second-console");
  sender.send(other);
  const auto after = sender.acks(kFlood + 1, 5.0);
  ASSERT_EQ(after.count(kFlood + 1), 1u);
  EXPECT_EQ(after.at(kFlood + 1).result, msg::AckResult::accepted) << after.at(kFlood + 1).reason;
}

TEST(CommandIntake, FullQueueRejectsAndSays) {
  IntakeConfig config = default_config();
  config.rate.per_source_burst = 1000.0;
  config.rate.total_burst = 1000.0;
  Fixture f(config);
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  const std::uint64_t n = msg::CommandQueue::capacity() + 3;
  for (std::uint64_t seq = 1; seq <= n; ++seq) sender.send(base(msg::CommandKind::start, seq));
  const auto acks = sender.acks(n, 10.0);
  ASSERT_EQ(acks.size(), n);
  for (std::uint64_t seq = 1; seq <= n; ++seq) {
    if (seq <= msg::CommandQueue::capacity()) {
      EXPECT_EQ(acks.at(seq).result, msg::AckResult::accepted) << seq;
    } else {
      EXPECT_EQ(acks.at(seq).result, msg::AckResult::rejected) << seq;
      EXPECT_NE(std::string(acks.at(seq).reason).find("command queue full"), std::string::npos);
    }
  }
  EXPECT_EQ(f.intake->stats().commands.queue_full, 3u);
}

TEST(CommandIntake, ExecutiveAcksArePublished) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  msg::Command c = base(msg::CommandKind::switch_terrain, 5);
  msg::copy_text(c.pack_id, "taunus");
  sender.send(c);
  ASSERT_EQ(sender.acks(1, 5.0).at(5).result, msg::AckResult::accepted);

  // the executive takes it, fails to load the pack, and says so
  msg::Command got{};
  ASSERT_TRUE(wait_until([&] { return f.queue.try_pop(got); }, 5.0));
  msg::CommandAck done{};
  msg::copy_text(done.source, msg::text_of(got.source));
  done.sequence = got.sequence;
  done.kind = static_cast<std::uint8_t>(got.kind);
  done.result = msg::AckResult::failed;
  msg::copy_text(done.reason, "taunus.pack: checksum of tile 3 wrong");
  ASSERT_TRUE(f.executive_acks.try_push(done));

  // the same source and sequence, now with the outcome
  ASSERT_TRUE(wait_until([&] { return sender.acks(1, 0.0).at(5).result == msg::AckResult::failed; }, 5.0));
  EXPECT_STREQ(sender.acks(1, 0.0).at(5).reason, "taunus.pack: checksum of tile 3 wrong");
  EXPECT_EQ(f.intake->stats().executive_acks, 1u);
}

TEST(CommandIntake, NewLimitsApplyAfterATerrainSwitch) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  // Taunus, UTM 32N
  CommandLimits taunus = sf_limits();
  taunus.min = {440000.0, 5550000.0, 0.0};
  taunus.max = {486000.0, 5596000.0, 1200.0};
  ASSERT_TRUE(f.intake->set_limits(taunus).ok());
  CommandLimits broken = taunus;
  broken.max.x_m = broken.min.x_m;
  const Status s = f.intake->set_limits(broken);
  EXPECT_NE(s.message().find("pack bounds are empty"), std::string::npos) << s.message();

  msg::Command c = base(msg::CommandKind::set_endpoints, 1);
  c.endpoints = {{450000.0, 5560000.0, 500.0}, {480000.0, 5590000.0, 600.0}};
  sender.send(c);
  EXPECT_EQ(sender.acks(1, 5.0).at(1).result, msg::AckResult::accepted);
}

TEST(CommandIntake, HealthReportsItsCounters) {
  Fixture f(default_config());
  ASSERT_NE(f.intake, nullptr);
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*f.console, PublisherConfig{}, f.intake.get());
  ASSERT_TRUE(pub.ok());
  Result<Reader> health = Reader::create(*f.operator_side, Topic::health);
  ASSERT_TRUE(health.ok());
  Sender sender(*f.operator_side);
  ASSERT_TRUE(sender.ready(5.0));
  sender.send(base(msg::CommandKind::start, 1));
  msg::Command bad = base(msg::CommandKind::set_segment_count, 2);
  bad.segment_count = 1;
  sender.send(bad);
  ASSERT_EQ(sender.acks(2, 5.0).size(), 2u);
  ASSERT_TRUE(health->wait_for_writers(1, 5.0).ok());

  std::uint64_t accepted = 0, rejected = 0;
  ASSERT_TRUE(wait_until(
      [&] {
        msg::HealthSample& h = (*pub)->health().back();
        h = msg::HealthSample{};
        (*pub)->health().publish();
        (void)health->take<visvol_msgs_msg_dds__LoopHealth_>(
            [&](const visvol_msgs_msg_dds__LoopHealth_& m, const dds_sample_info_t&) {
              accepted = m.commands_accepted;
              rejected = m.commands_rejected;
            });
        return accepted == 1 && rejected == 1;
      },
      5.0))
      << accepted << " " << rejected;
}

TEST(CommandIntake, RejectsBadConfiguration) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  msg::CommandQueue queue;
  IntakeConfig c = default_config();
  c.rate.total_per_s = -1.0;
  Result<std::unique_ptr<CommandIntake>> r = CommandIntake::start(*p, c, queue);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("rate limit"), std::string::npos);
  c = default_config();
  c.limits.max_segments = 100000;
  r = CommandIntake::start(*p, c, queue);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("max_segments 100000"), std::string::npos);
}

}  // namespace
}  // namespace visvol::dds
