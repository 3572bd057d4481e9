// visvol-console's threads, run as a user runs them (the 1 kHz loop, the
// monitor on the main thread, the DDS publisher and command intake, the hull
// builder, the path fitter, the thumbnail renderer), with a grasp from the
// simulated device and a constraint set over DDS. Labelled `threaded`: the
// ThreadSanitizer stage runs it, where a data race between them (the monitor
// once read the loop's counters directly) stops the console with a report.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "../fields/terrains.hpp"
#include "../tools/cli_runner.hpp"
#include "console_packs.hpp"
#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "tests/support/scratch.hpp"

namespace {

using visvol::test::slurp;

TEST(ConsoleThreads, ASessionWithCommandsRunsItsThreadsWithoutARace) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  const std::string pack = visvol::test::scratch_path("console_threads_pack");
  ASSERT_TRUE(visvol::storage::build_pack(visvol::fields::testing::fractal(65, 9),
                                          visvol::app::testing::small_pack_params(), "", pack)
                  .ok());
  const std::string script = visvol::test::scratch_path("console_threads_script");
  std::ofstream(script) << "0.2 move 0 0 0 0.1\n0.4 pull 20 0 -20 0.6\n1.2 release\n";

  ParticipantConfig pc;
  pc.domain_id = 227;  // this binary's own (console_test takes 223..226)
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto commands = Writer::create(**participant, Topic::command);
  auto acks = Reader::create(**participant, Topic::command_ack);
  ASSERT_TRUE(commands.ok() && acks.ok());

  const std::string out = visvol::test::scratch_path("console_threads");
  const std::string err = visvol::test::scratch_path("console_threads_err");
  int status = -1;
  // a budget that ThreadSanitizer's shadow memory fits in (the process alone
  // is 140 MiB under it)
  std::thread run([&] {
    const std::string cmd =
        std::string("timeout -k 5 120 ") + VISVOL_CONSOLE + " --pack " + pack +
        " --seconds 5 --domain 227 --priority 0 --no-lock --segments 24 --budget-mib 4096 --script " + script +
        " --out " + out + " </dev/null >/dev/null 2>" + err;
    const int rc = std::system(cmd.c_str());
    status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  });
  // a set of observers for the hull builder, once the intake is there
  // the intake acknowledges at once: its ack writer must reach us first
  const bool found = commands->wait_for_readers(1, 60.0).ok() && acks->wait_for_writers(1, 30.0).ok();
  bool sent = false;
  if (found) {
    auto opened = visvol::storage::Pack::open(pack);
    auto level = opened.ok() ? visvol::storage::PackLevel::open(*opened, 0)
                             : visvol::Result<visvol::storage::PackLevel>(opened.status());
    if (level.ok()) {
      const visvol::fields::VolumeGeometry g = level->geometry();
      Command hide{};
      hide.kind = CommandKind::set_constraints;
      hide.sequence = 1;
      copy_text(hide.source, "console_threads_test");
      hide.constraints.count = 1;
      hide.constraints.items[0] = {
          ConstraintKind::hidden_from,
          {g.origin_x + 32 * g.spacing_m, g.origin_y - 32 * g.spacing_m, level->post(32, 32) + 20.0},
          0.0};
      CommandMessage msg;
      sent = commands->write(&msg.fill(hide)) == DDS_RETCODE_OK;
    }
  }
  run.join();  // before any assertion: a joinable thread must not be destroyed
  ASSERT_TRUE(found) << "the console's command intake never appeared";
  ASSERT_TRUE(sent);
  const std::string report = slurp(err);
  EXPECT_EQ(status, 0) << report;
  EXPECT_EQ(report.find("ThreadSanitizer"), std::string::npos) << report;
  const nlohmann::json s = nlohmann::json::parse(slurp(out + "/summary.json"), nullptr, false);
  ASSERT_FALSE(s.is_discarded()) << "no summary.json: " << report;
  EXPECT_GT(s["loop"]["ticks"].get<int>(), 100);
  // every thread did its work: the command applied, its hulls built beside
  // the loop and put in force, pictures rendered, paths sent
  bool applied = false;
  auto taken = acks->take<visvol_msgs_msg_dds__CommandAck_>(
      [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
        const CommandAck ack = decode_ack(m);
        applied |= ack.sequence == 1u && ack.result == AckResult::applied;
      },
      16);
  ASSERT_TRUE(taken.ok());
  EXPECT_TRUE(applied) << report;
  EXPECT_EQ(s["commands"]["applied"].get<int>(), 1);
  EXPECT_EQ(s["constraints"]["built"].get<int>(), 1);
  EXPECT_EQ(s["constraints"]["sets_in_force"].get<int>(), 1);
  EXPECT_GE(s["thumbnails"]["rendered"].get<int>(), 1);
  EXPECT_GE(s["dds"]["paths"].get<int>(), 1);
  std::remove(pack.c_str());
  std::remove(script.c_str());
  std::remove(err.c_str());
}

}  // namespace
