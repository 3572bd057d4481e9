// Real Cyclone participants in this process and in a second one
// (dds_test_peer, spawned), on loopback, domain 215: paths cross the process
// boundary as ROS 2 CDR, a late-joining process gets the latest path, an
// offline publisher lingers until delivery, and commands from another process
// are validated and answered while this process goes on.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "dds_test_support.hpp"
#include "drivers/dds/command_intake.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "drivers/dds/path_publisher.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::Child;
using test::fill_path;
using test::loopback;
using test::make_participant;
using test::make_path;
using test::wait_until;
constexpr std::uint32_t kDomain = test::kDomainInterprocess;

std::vector<std::string> peer(const std::string& mode, const std::string& a, const std::string& b = "") {
  std::vector<std::string> argv = {VISVOL_DDS_PEER, mode, std::to_string(kDomain), test::process_namespace(), a};
  if (!b.empty()) argv.push_back(b);
  return argv;
}

std::vector<std::string> lines_starting(const std::string& text, const std::string& prefix) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) out.push_back(line.substr(prefix.size()));
  }
  return out;
}

TEST(Interprocess, PathsReachAnotherProcessAsRos2Cdr) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, PublisherConfig{});
  ASSERT_TRUE(pub.ok());

  Child listener(peer("listen", "5", "20"));
  ASSERT_TRUE(listener.started());
  ASSERT_TRUE(listener.wait_for_output("ready", 10.0)) << listener.output();
  ASSERT_TRUE(wait_until([&] { return (*pub)->path_subscribers() >= 1; }, 10.0));

  auto last = make_path(5, 6);
  for (std::uint64_t seq = 1; seq <= 5; ++seq) {
    fill_path((*pub)->path().back(), seq, 6);
    (*pub)->path().publish();
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // > 1/50 Hz
  }
  ASSERT_EQ(listener.wait(20.0), 0) << listener.output();
  const std::vector<std::string> updates = lines_starting(listener.output(), "update ");
  ASSERT_FALSE(updates.empty());
  EXPECT_EQ(updates.back(), "5 6");
  const std::vector<std::string> cdr = lines_starting(listener.output(), "path-cdr ");
  ASSERT_FALSE(cdr.empty());
  EXPECT_EQ(cdr.back(), test::hex(test::path_cdr(*last, kDefaultFrameId)));
}

TEST(Interprocess, LateJoiningProcessGetsTheLatestPath) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());
  for (std::uint64_t seq = 1; seq <= 3; ++seq) ASSERT_TRUE((*pub)->publish(*make_path(seq, 4)).ok());

  Child late(peer("listen", "3", "20"));
  ASSERT_TRUE(late.started());
  ASSERT_EQ(late.wait(20.0), 0) << late.output();
  EXPECT_EQ(lines_starting(late.output(), "update "), std::vector<std::string>{"3 4"});
}

TEST(Interprocess, OfflinePublisherLingersUntilDelivered) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  QosPtr qos = reader_qos(Topic::path_update);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  Result<Reader> reader = Reader::create(*p, Topic::path_update, qos.get());
  ASSERT_TRUE(reader.ok());

  Child planner(peer("publish", "20", "10"));
  ASSERT_TRUE(planner.started());
  ASSERT_EQ(planner.wait(30.0), 0) << planner.output();
  EXPECT_NE(planner.output().find("delivered"), std::string::npos);

  // the planner has exited: what it published is here, the final path last
  std::vector<std::uint64_t> seqs;
  bool converged = false;
  wait_until(
      [&] {
        (void)reader->take<visvol_msgs_msg_dds__PathUpdate_>(
            [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
              seqs.push_back(m.sequence_number);
              converged = m.converged;
            });
        return !seqs.empty() && seqs.back() == 20;
      },
      2.0);
  ASSERT_FALSE(seqs.empty());
  EXPECT_EQ(seqs.back(), 20u);
  EXPECT_TRUE(converged);
}

// An intake for a pack of 1000 m a side.
IntakeConfig kilometre_box() {
  IntakeConfig config;
  config.limits.min = {0.0, 0.0, 0.0};
  config.limits.max = {1000.0, 1000.0, 1000.0};
  return config;
}

TEST(Interprocess, CommandsFromAnotherProcessAreValidatedAndAnswered) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  msg::CommandQueue queue;
  Result<std::unique_ptr<CommandIntake>> intake = CommandIntake::start(*p, kilometre_box(), queue);
  ASSERT_TRUE(intake.ok());

  Child sender(peer("commands", "20"));
  ASSERT_TRUE(sender.started());
  ASSERT_EQ(sender.wait(30.0), 0) << sender.output();
  const std::string out = sender.output();
  EXPECT_NE(out.find("ack 1 rejected start_m.x: nan is not a finite number"), std::string::npos) << out;
  EXPECT_NE(out.find("ack 2 rejected segment_count: 1000000 is outside the 2..511"), std::string::npos) << out;
  EXPECT_NE(out.find("ack 3 rejected kind: 250 is not a known command"), std::string::npos) << out;
  EXPECT_NE(out.find("ack 4 accepted"), std::string::npos) << out;

  msg::Command c{};
  ASSERT_TRUE(queue.try_pop(c));
  EXPECT_EQ(c.kind, msg::CommandKind::start);
  EXPECT_EQ(msg::text_of(c.source), "peer");
  EXPECT_FALSE(queue.try_pop(c));
  // and this process carries on: the same intake answers a second sender (a
  // source of its own, so the first one's stored acks cannot pass for its own)
  Child again(peer("commands", "20", "peer2"));
  ASSERT_EQ(again.wait(30.0), 0) << again.output();
  EXPECT_NE(again.output().find("ack 4 accepted"), std::string::npos) << again.output();
  EXPECT_EQ((*intake)->stats().commands.received, 8u);
}

// A sender without visvol's sample limit (its own configuration allows 64
// MiB): its 2 MiB command is dropped by this process's Cyclone as it arrives,
// unanswered, and the intake answers the next sender (25 million
// constraints took a console to 950 MiB of locked memory before).
TEST(Interprocess, ASampleOverTheLimitFromAnotherProcessIsDroppedAsItArrives) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  msg::CommandQueue queue;
  Result<std::unique_ptr<CommandIntake>> intake = CommandIntake::start(*p, kilometre_box(), queue);
  ASSERT_TRUE(intake.ok());
  Child sender(peer("oversize", "3"));
  ASSERT_TRUE(sender.started());
  ASSERT_EQ(sender.wait(30.0), 0) << sender.output();
  EXPECT_NE(sender.output().find("sent"), std::string::npos) << sender.output();
  EXPECT_EQ(sender.output().find("ack "), std::string::npos) << sender.output();
  EXPECT_EQ((*intake)->stats().commands.received, 0u);
  Child next(peer("commands", "20", "after"));
  ASSERT_EQ(next.wait(30.0), 0) << next.output();
  EXPECT_NE(next.output().find("ack 4 accepted"), std::string::npos) << next.output();
  EXPECT_EQ((*intake)->stats().commands.received, 4u);
}

}  // namespace
}  // namespace visvol::dds
