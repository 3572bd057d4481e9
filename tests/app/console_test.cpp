// visvol-console as an operator runs it: options, a run with the simulated
// device, its outputs, and the DDS side (paths, health, a command and its
// acknowledgements) seen from another participant (domain 223, loopback).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "../tools/cli_runner.hpp"
#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "../fields/terrains.hpp"

namespace {

using visvol::test::Outcome;
using visvol::test::slurp;

Outcome console(const std::string& args) {
  // the runner's binary is visvol; point it at the console instead
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(getpid());
  const std::string out = dir + "/console_out_" + tag, err = dir + "/console_err_" + tag;
  const std::string cmd = std::string(VISVOL_CONSOLE) + " " + args + " </dev/null >" + out + " 2>" + err;
  const int rc = std::system(cmd.c_str());
  Outcome r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

// The console's test packs: small, two levels of detail.
visvol::storage::PackBuildParams small_pack_params() {
  visvol::storage::PackBuildParams p;
  p.field.nz = 32;
  p.field.ceiling_m = 200;
  p.field.range_posts = 8;
  p.lod_levels = 2;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  return p;
}

class Console : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pack_ = new std::string(::testing::TempDir() + "/console_" + std::to_string(getpid()) + ".vvp");
    ASSERT_TRUE(
        visvol::storage::build_pack(visvol::fields::testing::fractal(97, 5), small_pack_params(), "", *pack_).ok());
    // grab at 0.5 s, pull, let go at 2 s
    script_ = new std::string(::testing::TempDir() + "/console_script_" + std::to_string(getpid()) + ".txt");
    std::ofstream(*script_) << "0.3 move 0 0 0 0.1\n0.5 pull 20 0 -20 1.0\n2.0 release\n";
  }
  static void TearDownTestSuite() {
    std::remove(pack_->c_str());
    std::remove(script_->c_str());
    delete pack_;
    delete script_;
  }
  static std::string out_dir(const std::string& name) {
    return ::testing::TempDir() + "/console_" + name + "_" + std::to_string(getpid());
  }
  static std::string* pack_;
  static std::string* script_;
};
std::string* Console::pack_ = nullptr;
std::string* Console::script_ = nullptr;

TEST_F(Console, HelpAndBadOptions) {
  const Outcome h = console("--help");
  EXPECT_EQ(h.status, 0);
  for (const char* o : {"--pack", "--budget-mib", "--device", "--domain", "--seconds"}) {
    EXPECT_NE(h.out.find(o), std::string::npos) << o;
  }
  for (const std::string& args :
       {std::string("--pack /nonexistent.vvp"), "--pack " + *pack_ + " --segments 1",
        "--pack " + *pack_ + " --device socketcan", "--pack " + *pack_ + " --objective sideways",
        "--pack " + *pack_ + " --from 1 2 3 --no-dds", "--pack " + *pack_ + " --level 7 --no-dds",
        "--pack " + *pack_ + " --thumbnail-size 10x10 --no-dds", "--pack " + *pack_ + " --thumbnail-view side"}) {
    const Outcome r = console(args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("visvol-console: "), std::string::npos) << args;
  }
}

TEST_F(Console, RunsWithTheSimulatedDeviceAndWritesItsOutputs) {
  const std::string out = out_dir("run");
  const Outcome r = console("--pack " + *pack_ + " --seconds 3 --no-dds --priority 0 --no-lock --segments 32 --script " +
                            *script_ + " --out " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("outputs: "), std::string::npos);
  const nlohmann::json s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_GT(s["loop"]["ticks"].get<int>(), 1000);
  // Once settled the loop thread touches only pages it touched before: no
  // fault at all in the optimised build. Under AddressSanitizer the shadow of
  // newly touched memory is mapped lazily, and such a fault that retries
  // behind another thread's mmap is counted as major without any disk I/O.
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_EQ(s["loop"]["major_faults_after_settle"].get<int>(), 0);
  EXPECT_EQ(s["loop"]["minor_faults_after_settle"].get<int>(), 0);
#endif
  EXPECT_LE(s["path"]["fc_end"].get<double>(), s["path"]["fc_start"].get<double>());
  EXPECT_EQ(s["device"]["state"], "operational");
  EXPECT_EQ(s["device"]["grasps"].get<int>(), 1);
  EXPECT_LE(s["device"]["simulated"]["max_force_n"].get<double>(), 1.4 + 1e-9);
  EXPECT_LE(s["memory"]["rss_peak_mib"].get<double>(), s["memory"]["budget_mib"].get<double>());
  const std::string csv = slurp(out + "/path.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 34);  // header + 33 vertices
  const std::string health = slurp(out + "/health.csv");
  EXPECT_GE(std::count(health.begin(), health.end(), '\n'), 3);  // header + a line a second
  EXPECT_GE(s["thumbnails"]["rendered"].get<int>(), 1);  // at least the one where the rope ended
  EXPECT_EQ(s["thumbnails"]["failed"].get<int>(), 0);
  EXPECT_EQ(slurp(out + "/thumbnail.png").substr(0, 4), "\x89PNG");
}

TEST_F(Console, PublishesOnDdsAndTakesCommands) {
  using namespace visvol::dds;
  ParticipantConfig pc;
  pc.domain_id = 223;
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto paths = Reader::create(**participant, Topic::path_update);
  auto acks = Reader::create(**participant, Topic::command_ack);
  auto commands = Writer::create(**participant, Topic::command);
  auto thumbnails = Reader::create(**participant, Topic::thumbnail);
  ASSERT_TRUE(paths.ok() && acks.ok() && commands.ok() && thumbnails.ok());

  const std::string out = out_dir("dds");
  Outcome r;
  std::thread run([&] {
    r = console("--pack " + *pack_ + " --seconds 4 --domain 223 --priority 0 --no-lock --segments 32 --script none --out " +
                out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  Command show{};
  show.kind = CommandKind::set_objective;
  show.sequence = 7;
  show.objective = Objective::show;
  copy_text(show.source, "console_test");
  CommandMessage msg;
  ASSERT_EQ(commands->write(&msg.fill(show)), DDS_RETCODE_OK);
  // stay hidden from a point 50 m above the middle of the pack
  auto pack = visvol::storage::Pack::open(*pack_);
  ASSERT_TRUE(pack.ok());
  auto level = visvol::storage::PackLevel::open(*pack, 0);
  ASSERT_TRUE(level.ok());
  const visvol::fields::VolumeGeometry g = level->geometry();
  const int ci = g.nx / 2, cj = g.ny / 2;
  Command hide{};
  hide.kind = CommandKind::set_constraints;
  hide.sequence = 8;
  copy_text(hide.source, "console_test");
  hide.constraints.count = 1;
  hide.constraints.items[0].kind = ConstraintKind::hidden_from;
  hide.constraints.items[0].position.x_m = g.origin_x + ci * g.spacing_m;
  hide.constraints.items[0].position.y_m = g.origin_y - cj * g.spacing_m;
  hide.constraints.items[0].position.z_m = level->post(ci, cj) + 50.0;
  ASSERT_EQ(commands->write(&msg.fill(hide)), DDS_RETCODE_OK);
  run.join();
  ASSERT_EQ(r.status, 0) << r.err;

  int applied = 0, accepted = 0;
  auto a = acks->take<visvol_msgs_msg_dds__CommandAck_>(
      [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
        const CommandAck ack = decode_ack(m);
        EXPECT_TRUE(ack.sequence == 7u || ack.sequence == 8u) << ack.sequence;
        applied += ack.result == AckResult::applied;
        accepted += ack.result == AckResult::accepted;
      },
      16);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(accepted, 2);
  EXPECT_EQ(applied, 2);
  int received = 0;
  auto p = paths->take<visvol_msgs_msg_dds__PathUpdate_>(
      [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
        ++received;
        EXPECT_EQ(m.positions_m._length, 33u);
        EXPECT_EQ(m.objective, 2);  // show, after the command
      },
      64);
  ASSERT_TRUE(p.ok());
  EXPECT_GE(received, 1);
  int pictures = 0;
  auto t = thumbnails->take<sensor_msgs_msg_dds__CompressedImage_>(
      [&](const sensor_msgs_msg_dds__CompressedImage_& m, const dds_sample_info_t&) {
        ++pictures;
        EXPECT_STREQ(m.format, "png");
        ASSERT_GT(m.data._length, 8u);
        EXPECT_EQ(m.data._buffer[1], 'P');
      },
      8);
  ASSERT_TRUE(t.ok());
  EXPECT_GE(pictures, 1);
  const nlohmann::json s = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_GT(s["dds"]["paths"].get<int>(), 50);
  EXPECT_EQ(s["commands"]["applied"].get<int>(), 2);
  // the hidden-from hull was built beside the loop and put in force
  EXPECT_EQ(s["constraints"]["built"].get<int>(), 1);
  EXPECT_EQ(s["constraints"]["in_force"].get<int>(), 1);
  EXPECT_EQ(s["constraints"]["refused"].get<int>(), 0);
}


// switch-terrain to a --terrain pack: the session on the first pack ends
// (its outputs kept in session-1-ID) and one on the other pack runs for the
// time left, writing the outputs; an unknown pack id is refused by the intake.
TEST_F(Console, SwitchesTerrainOnCommand) {
  using namespace visvol::dds;
  const std::string other = ::testing::TempDir() + "/console_b_" + std::to_string(getpid()) + ".vvp";
  ASSERT_TRUE(visvol::storage::build_pack(visvol::fields::testing::fractal(65, 9), small_pack_params(), "", other).ok());
  const std::string first_id = "console_" + std::to_string(getpid()), other_id = "console_b_" + std::to_string(getpid());

  ParticipantConfig pc;
  pc.domain_id = 225;
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto commands = Writer::create(**participant, Topic::command);
  auto acks = Reader::create(**participant, Topic::command_ack);
  ASSERT_TRUE(commands.ok() && acks.ok());
  const std::string out = out_dir("switch");
  Outcome r;
  std::thread run([&] {
    r = console("--pack " + *pack_ + " --terrain " + other + " --seconds 8 --domain 225 --priority 0 --no-lock "
                "--segments 32 --script none --thumbnail-view none --out " + out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  CommandMessage msg;
  Command unknown{};
  unknown.kind = CommandKind::switch_terrain;
  unknown.sequence = 1;
  copy_text(unknown.source, "console_test");
  copy_text(unknown.pack_id, "no_such_pack");
  ASSERT_EQ(commands->write(&msg.fill(unknown)), DDS_RETCODE_OK);
  Command go = unknown;
  go.sequence = 2;
  copy_text(go.pack_id, other_id);
  ASSERT_EQ(commands->write(&msg.fill(go)), DDS_RETCODE_OK);
  run.join();
  std::remove(other.c_str());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("switch-terrain"), std::string::npos) << r.err;

  int refused = 0, applied = 0;
  auto a = acks->take<visvol_msgs_msg_dds__CommandAck_>(
      [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
        const CommandAck ack = decode_ack(m);
        refused += ack.sequence == 1 && ack.result == AckResult::rejected;
        applied += ack.sequence == 2 && ack.result == AckResult::applied;
      },
      16);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(refused, 1);
  EXPECT_EQ(applied, 1);

  const nlohmann::json before =
      nlohmann::json::parse(slurp(out + "/session-1-" + first_id + "/summary.json"));
  EXPECT_EQ(before["pack_id"], first_id);
  EXPECT_EQ(before["switched_to"], other_id);
  const nlohmann::json after = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(after["pack_id"], other_id);
  EXPECT_EQ(after["session"], 2);
  EXPECT_EQ(after["switched_from"], first_id);
  EXPECT_EQ(after["switched_to"], "");
  EXPECT_GT(after["loop"]["ticks"].get<int>(), 1000);  // it ran on the other pack
  const std::string csv = slurp(out + "/path.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 34);  // header + 33 vertices
}

}  // namespace
