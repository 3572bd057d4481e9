// visvol-echo (tools/echo) as an operator uses it, against a console side in
// this process: command intake and the publisher thread, on loopback,
// domain 216.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dds_test_support.hpp"
#include "drivers/dds/command_intake.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::Child;
using test::fill_path;
using test::loopback;
using test::make_participant;
constexpr std::uint32_t kDomain = test::kDomainEcho;

std::vector<std::string> echo(std::vector<std::string> args) {
  std::vector<std::string> argv = {VISVOL_ECHO, "--domain", std::to_string(kDomain), "--namespace",
                                   test::process_namespace()};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

struct Console {
  std::unique_ptr<Participant> participant = make_participant(loopback(kDomain));
  msg::CommandQueue queue;
  msg::AckQueue executive_acks;
  std::unique_ptr<CommandIntake> intake;
  Console() {
    if (!participant) return;
    IntakeConfig config;
    config.limits.min = {540000.0, 4180000.0, -10.0};
    config.limits.max = {551100.0, 4194000.0, 900.0};
    config.limits.max_segments = 200;
    Result<std::unique_ptr<CommandIntake>> r = CommandIntake::start(*participant, config, queue, &executive_acks);
    EXPECT_TRUE(r.ok());
    if (r.ok()) intake = std::move(*r);
  }
};

TEST(Echo, AcceptedCommandExitsZeroAndReachesTheQueue) {
  Console console;
  ASSERT_NE(console.intake, nullptr);
  Child c(echo({"command", "--source", "operator-1", "--sequence", "7", "set-objective", "hide"}));
  ASSERT_EQ(c.wait(30.0), 0) << c.output();
  EXPECT_NE(c.output().find("ack source=\"operator-1\" seq=7 kind=set-objective result=accepted"), std::string::npos)
      << c.output();
  msg::Command got{};
  ASSERT_TRUE(console.queue.try_pop(got));
  EXPECT_EQ(got.kind, msg::CommandKind::set_objective);
  EXPECT_EQ(got.objective, msg::Objective::hide);
  EXPECT_EQ(got.sequence, 7u);

  Child e(echo({"command", "set-endpoints", "541000", "4181000", "120", "550000", "4190000", "80"}));
  ASSERT_EQ(e.wait(30.0), 0) << e.output();
  ASSERT_TRUE(console.queue.try_pop(got));
  EXPECT_EQ(got.endpoints.end.y_m, 4190000.0);
  EXPECT_EQ(msg::text_of(got.source).rfind("visvol-echo@", 0), 0u);

  Child k(
      echo({"command", "set-constraints", "--hidden-from", "545000,4185000,10", "--hidden-from", "546000,4186000,20",
            "--visible-to", "547000,4187000,30", "--clearance", "50", "--max-agl", "300", "--max-altitude", "800"}));
  ASSERT_EQ(k.wait(30.0), 0) << k.output();
  ASSERT_TRUE(console.queue.try_pop(got));
  ASSERT_EQ(got.constraints.count, 6u);
  EXPECT_EQ(got.constraints.items[0].kind, msg::ConstraintKind::hidden_from);
  EXPECT_EQ(got.constraints.items[1].kind, msg::ConstraintKind::hidden_from);
  EXPECT_EQ(got.constraints.items[1].position.z_m, 20.0);
  EXPECT_EQ(got.constraints.items[2].kind, msg::ConstraintKind::visible_to);
  EXPECT_EQ(got.constraints.items[3].height_m, 50.0);
  EXPECT_EQ(got.constraints.items[4].kind, msg::ConstraintKind::max_agl);
  EXPECT_EQ(got.constraints.items[4].height_m, 300.0);
  EXPECT_EQ(got.constraints.items[5].kind, msg::ConstraintKind::max_altitude);
  EXPECT_EQ(got.constraints.items[5].height_m, 800.0);
}

TEST(Echo, RejectedCommandPrintsTheReasonAndExitsOne) {
  Console console;
  ASSERT_NE(console.intake, nullptr);
  Child c(echo({"command", "set-segments", "5000"}));
  ASSERT_EQ(c.wait(30.0), 1) << c.output();
  EXPECT_NE(c.output().find("result=rejected reason=\"segment_count: 5000 is outside the 2..200 segments "
                            "reserved\""),
            std::string::npos)
      << c.output();
  Child t(echo({"command", "switch-terrain", "alps"}));
  ASSERT_EQ(t.wait(30.0), 1) << t.output();
  EXPECT_NE(t.output().find("this console has no other packs"), std::string::npos) << t.output();
  Child k(echo({"command", "set-constraints", "--clearance", "50", "--max-agl", "20"}));
  ASSERT_EQ(k.wait(30.0), 1) << k.output();
  EXPECT_NE(k.output().find("max-agl 20 m is not above the clearance 50 m"), std::string::npos) << k.output();
  msg::Command got{};
  EXPECT_FALSE(console.queue.try_pop(got));
}

TEST(Echo, WaitAppliedWaitsForTheExecutive) {
  Console console;
  ASSERT_NE(console.intake, nullptr);
  Child c(echo({"command", "--wait-applied", "--timeout", "20", "--sequence", "3", "start"}));
  // the executive takes the command and reports it applied
  msg::Command got{};
  ASSERT_TRUE(test::wait_until([&] { return console.queue.try_pop(got); }, 20.0)) << c.output();
  ASSERT_TRUE(c.wait_for_output("result=accepted", 20.0)) << c.output();
  msg::CommandAck done{};
  msg::copy_text(done.source, msg::text_of(got.source));
  done.sequence = got.sequence;
  done.kind = static_cast<std::uint8_t>(got.kind);
  done.result = msg::AckResult::applied;
  ASSERT_TRUE(console.executive_acks.try_push(done));
  ASSERT_EQ(c.wait(30.0), 0) << c.output();
  EXPECT_NE(c.output().find("seq=3 kind=start result=applied"), std::string::npos) << c.output();
}

TEST(Echo, NoConsoleIsAFailureNotAHang) {
  Child c(echo({"command", "--timeout", "0.5", "stop"}));
  ASSERT_EQ(c.wait(30.0), 1) << c.output();
  EXPECT_NE(c.output().find("no command intake on domain 216"), std::string::npos) << c.output();
}

TEST(Echo, BadArgumentsExitTwoWithOneLine) {
  const std::vector<std::vector<std::string>> cases = {
      {"command", "set-objective", "maybe"},
      {"command", "set-endpoints", "1", "2", "nan", "4", "5", "6"},
      {"command", "set-endpoints", "1", "2", "3"},
      {"command", "set-constraints", "--visible-to", "1,2"},
      {"command", "set-constraints", "--max-agl", "nan"},
      {"command", "set-constraints", "--max-altitude", "high"},
      {"command", "switch-terrain", "../x"},
      {"command", "--source", "", "start"},
      {"path", "--count", "-3"},
      // NaN passed CLI11's range: a path watch that never timed out
      {"path", "--timeout", "nan"},
      {"command", "--timeout", "nan", "stop"},
      // decimal only: strtod read 0x10 as sixteen
      {"command", "set-constraints", "--hidden-from", "0x10,2,3"},
      {"nonsense"},
  };
  for (const auto& args : cases) {
    Child c(echo(args));
    EXPECT_EQ(c.wait(30.0), 2) << args.front() << " " << args.back() << ": " << c.output();
    const std::string out = c.output();
    EXPECT_EQ(out.rfind("visvol-echo: ", 0), 0u) << out;
    EXPECT_EQ(out.find('\n'), out.size() - 1) << "more than one line: " << out;
  }
  Child domain({VISVOL_ECHO, "--domain", "233", "path"});
  EXPECT_EQ(domain.wait(30.0), 2) << domain.output();
  Child help({VISVOL_ECHO, "--help"});
  EXPECT_EQ(help.wait(30.0), 0);
  EXPECT_NE(help.output().find("command"), std::string::npos);
  EXPECT_NE(help.output().find("Exit status"), std::string::npos);
}

TEST(Echo, PrintsPathUpdatesAndHealth) {
  Console console;
  ASSERT_NE(console.participant, nullptr);
  Result<std::unique_ptr<LivePublisher>> pub =
      LivePublisher::start(*console.participant, PublisherConfig{}, console.intake.get());
  ASSERT_TRUE(pub.ok());
  fill_path((*pub)->path().back(), 41, 3);
  (*pub)->path().publish();
  ASSERT_TRUE(test::wait_until([&] { return (*pub)->stats().paths == 1; }, 5.0));

  // a late joiner: the latest path is waiting for it
  Child c(echo({"path", "--count", "1", "--timeout", "20", "--vertices"}));
  ASSERT_EQ(c.wait(30.0), 0) << c.output();
  const std::string out = c.output();
  EXPECT_NE(out.find("path seq=41 "), std::string::npos) << out;
  EXPECT_NE(out.find("frame=\"visvol_world\" pack=\"sf_north\" objective=hide vertices=3"), std::string::npos) << out;
  EXPECT_NE(out.find("  [2] x_m=544020.000 y_m=4189000.000 z_m=191.000"), std::string::npos) << out;
  EXPECT_NE(out.find(" mode=pull spool_paid_out_m=0.000"), std::string::npos) << out;

  // the same as one JSON object a line, for scripts
  Child j(echo({"--json", "path", "--count", "1", "--timeout", "20", "--vertices"}));
  ASSERT_EQ(j.wait(30.0), 0) << j.output();
  const std::string json = j.output();
  for (const char* part : {"{\"clearance_m\":[", "\"frame_id\":\"visvol_world\"", "\"mode\":\"pull\"",
                           "\"objective\":\"hide\"", "\"pack_id\":\"sf_north\"", "[544020.0,4189000.0,191.0]",
                           "\"sequence_number\":41", "\"topic\":\"path\"", "\"vertices\":3"}) {
    EXPECT_NE(json.find(part), std::string::npos) << part << " in " << json;
  }

  Child h(echo({"health", "--count", "1", "--timeout", "20"}));
  ASSERT_TRUE(h.wait_for_output("watching", 20.0)) << h.output();
  // health is volatile: publish while it listens
  ASSERT_TRUE(test::wait_until(
      [&] {
        msg::HealthSample& s = (*pub)->health().back();
        s = msg::HealthSample{};
        s.sequence = 5;
        s.period_us = 1000.0;
        (*pub)->health().publish();
        h.drain(20);
        return h.output().find("health seq=5") != std::string::npos;
      },
      20.0))
      << h.output();
  EXPECT_EQ(h.wait(30.0), 0) << h.output();
}

TEST(Echo, WatchGivesUpAfterTheTimeout) {
  Child c(echo({"path", "--count", "1", "--timeout", "0.3"}));
  EXPECT_EQ(c.wait(30.0), 1) << c.output();
  EXPECT_NE(c.output().find("0 of 1 message(s)"), std::string::npos) << c.output();
}

}  // namespace
}  // namespace visvol::dds
