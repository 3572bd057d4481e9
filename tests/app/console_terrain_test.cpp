// visvol-console's terrains: switching packs on command, its catalogue,
// a bad pack at start-up, a switch that cannot start.
#include "console_fixture.hpp"

namespace {

using namespace visvol::app::console_process_test;

// switch-terrain to a --terrain pack: the session on the first pack ends
// (its outputs kept in session-1-ID) and one on the other pack runs for the
// time left, writing the outputs; an unknown pack id is refused by the intake.
TEST_F(Console, SwitchesTerrainOnCommand) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  const std::string other = ::testing::TempDir() + "/console_b_" + std::to_string(getpid()) + ".vvp";
  ASSERT_TRUE(
      visvol::storage::build_pack(visvol::fields::testing::fractal(65, 9), small_pack_params(), "", other).ok());
  const std::string first_id = "console_" + std::to_string(getpid()),
                    other_id = "console_b_" + std::to_string(getpid());

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
    r = console("--pack " + *pack_ + " --terrain " + other +
                " --seconds 8 --domain 225 --priority 0 --no-lock "
                "--segments 32 --script none --thumbnail-view none --out " +
                out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  // the intake acknowledges at once: its ack writer must reach us first
  ASSERT_TRUE(acks->wait_for_writers(1, 10.0).ok()) << "the console's acknowledgements never appeared";
  CommandMessage msg;
  Command unknown{};
  unknown.kind = CommandKind::switch_terrain;
  unknown.sequence = 1;
  copy_text(unknown.source, "console_test");
  copy_text(unknown.pack_id, "no_such_pack");
  ASSERT_EQ(commands->write(&msg.fill(unknown)), DDS_RETCODE_OK);
  int refused = 0, applied = 0;
  auto count_acks = [&] {
    auto a = acks->take<visvol_msgs_msg_dds__CommandAck_>(
        [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
          const CommandAck ack = decode_ack(m);
          refused += ack.sequence == 1 && ack.result == AckResult::rejected;
          applied += ack.sequence == 2 && ack.result == AckResult::applied;
        },
        16);
    EXPECT_TRUE(a.ok());
  };
  // as an operator would: the refusal read before the next command (the
  // switch ends this session's participant, and with it what it had not sent)
  for (int i = 0; i < 100 && refused == 0; ++i) {
    (void)acks->wait(0.1);
    count_acks();
  }
  ASSERT_EQ(refused, 1) << "the unknown pack was not refused within 10 s";
  Command go = unknown;
  go.sequence = 2;
  copy_text(go.pack_id, other_id);
  ASSERT_EQ(commands->write(&msg.fill(go)), DDS_RETCODE_OK);
  run.join();
  std::remove(other.c_str());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("switch-terrain"), std::string::npos) << r.err;
  count_acks();
  EXPECT_EQ(refused, 1);
  EXPECT_EQ(applied, 1);

  const nlohmann::json before = nlohmann::json::parse(slurp(out + "/session-1-" + first_id + "/summary.json"));
  EXPECT_EQ(before["pack_id"], first_id);
  EXPECT_EQ(before["switched_to"], other_id);
  const nlohmann::json after = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(after["pack_id"], other_id);
  EXPECT_EQ(after["session"], 2);
  EXPECT_EQ(after["switched_from"], first_id);
  EXPECT_EQ(after["switched_to"], "");
  EXPECT_GT(after["loop"]["ticks"].get<int>(), 1000);  // it ran on the other pack
  EXPECT_EQ(path_rows(out + "/path.csv").size(),
            static_cast<std::size_t>(after["path"]["flyable"]["vertices"].get<int>()));
}

// A pack of the --catalogue folder, verified while the session runs, is one
// a switch-terrain may name; a damaged one beside it is listed as refused.
TEST_F(Console, SwitchesToAVerifiedPackOfItsCatalogue) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  const std::string dir = visvol::test::scratch_path("console_catalogue");
  ASSERT_EQ(std::system(("rm -rf '" + dir + "' && mkdir '" + dir + "'").c_str()), 0);
  ASSERT_TRUE(
      visvol::storage::build_pack(visvol::fields::testing::fractal(65, 9), small_pack_params(), "", dir + "/valley.vvp")
          .ok());
  ASSERT_TRUE(visvol::storage::build_pack(visvol::fields::testing::fractal(65, 10), small_pack_params(), "",
                                          dir + "/damaged.vvp")
                  .ok());
  ASSERT_EQ(truncate((dir + "/damaged.vvp").c_str(), 8192), 0);
  const std::string first_id = "console_" + std::to_string(getpid());

  ParticipantConfig pc;
  pc.domain_id = 229;
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto commands = Writer::create(**participant, Topic::command);
  auto acks = Reader::create(**participant, Topic::command_ack);
  auto listing = Reader::create(**participant, Topic::terrain_catalogue);
  ASSERT_TRUE(commands.ok() && acks.ok() && listing.ok());
  const std::string out = out_dir("catalogue");
  Outcome r;
  std::thread run([&] {
    r = console("--pack " + *pack_ + " --catalogue " + dir +
                " --seconds 10 --domain 229 --priority 0 --no-lock "
                "--segments 32 --script none --thumbnail-view none --out " +
                out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  ASSERT_TRUE(acks->wait_for_writers(1, 10.0).ok()) << "the console's acknowledgements never appeared";
  // asked until the first session ends (its outputs written): refused while
  // the pack is being verified (the applied one's ack may go with the session)
  const std::string first_summary = out + "/session-1-" + first_id + "/summary.json";
  CommandMessage msg;
  Command go{};
  go.kind = CommandKind::switch_terrain;
  copy_text(go.source, "console_test");
  copy_text(go.pack_id, "valley");
  for (std::uint32_t seq = 1; seq <= 40 && access(first_summary.c_str(), F_OK) != 0; ++seq) {
    go.sequence = seq;
    ASSERT_EQ(commands->write(&msg.fill(go)), DDS_RETCODE_OK);
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  run.join();
  ASSERT_EQ(r.status, 0) << r.err;
  // on DDS: the catalogue as verified (transient-local: the last of each session)
  auto seen = std::make_unique<TerrainCatalogue>();
  bool listed_verified = false, listed_refused = false;
  auto taken = listing->take<visvol_msgs_msg_dds__TerrainCatalogue_>(
      [&](const visvol_msgs_msg_dds__TerrainCatalogue_& m, const dds_sample_info_t&) {
        ASSERT_TRUE(decode_catalogue(m, *seen).ok());
        for (std::uint32_t i = 0; i < seen->count; ++i) {
          const CatalogueEntry& e = seen->entries[i];
          listed_verified |= text_of(e.pack_id) == "valley" && e.state == CatalogueState::verified && e.levels == 2;
          listed_refused |= text_of(e.pack_id) == "damaged" && e.state == CatalogueState::refused &&
                            text_of(e.reason).find("truncated") != std::string_view::npos;
        }
      },
      16);
  ASSERT_TRUE(taken.ok());
  EXPECT_TRUE(listed_verified) << "valley, verified, not on rt/visvol/terrain_catalogue";
  EXPECT_TRUE(listed_refused) << "damaged, refused with its reason, not on rt/visvol/terrain_catalogue";
  EXPECT_NE(r.err.find("catalogue: valley verified"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("catalogue: damaged refused"), std::string::npos) << r.err;
  const nlohmann::json before = nlohmann::json::parse(slurp(out + "/session-1-" + first_id + "/summary.json"));
  EXPECT_EQ(before["switched_to"], "valley");
  std::map<std::string, std::string> states;
  for (const auto& e : before["catalogue"]["entries"]) states[e["id"]] = e["state"];
  EXPECT_EQ(states["valley"], "verified");
  EXPECT_EQ(states["damaged"], "refused");
  const nlohmann::json after = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(after["pack_id"], "valley");
  EXPECT_EQ(after["pack"], dir + "/valley.vvp");
  EXPECT_GT(after["loop"]["ticks"].get<int>(), 500);  // it ran on the catalogue's pack
  ASSERT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

// A --terrain pack is checked at start-up as a switch would need it, tiles
// included: a bad one refuses the start (status 2), naming it.
TEST_F(Console, RefusesToStartWithABadTerrainPack) {
  const std::string bad = ::testing::TempDir() + "/console_bad_" + std::to_string(getpid()) + ".vvp";
  const std::string out = out_dir("bad_terrain");
  struct Case {
    const char* what;
    std::function<void(visvol::storage::testing::CraftedPack&, const std::string&)> make;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"a tile whose checksum fails",
       [](visvol::storage::testing::CraftedPack& p, const std::string& path) {
         p.write(path);
         // one byte of the last tile, after the checksums were written
         const visvol::storage::TileEntry& t = p.tile(1, visvol::storage::Layer::tff, 0, 0);
         std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
         f.seekp(static_cast<std::streamoff>(t.offset + 5));
         f.put('\x7f');
       },
       "tff tile (0, 0) of level 1: checksum mismatch"},
      {"a NaN height with consistent checksums",
       [](visvol::storage::testing::CraftedPack& p, const std::string& path) {
         p.set_height(0, 3, 4, NAN);
         p.write(path);
       },
       "post (3, 4) has height nan"},
  };
  for (const Case& c : cases) {
    visvol::storage::testing::CraftedPack pack(*pack_);
    c.make(pack, bad);
    const Outcome r = console("--pack " + *pack_ + " --terrain " + bad +
                              " --seconds 2 --no-dds --priority 0 --no-lock "
                              "--script none --thumbnail-view none --out " +
                              out);
    EXPECT_EQ(r.status, 2) << c.what << ": " << r.err;
    EXPECT_NE(r.err.find("--terrain " + bad + ": "), std::string::npos) << c.what << ": " << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.what << ": " << r.err;
    EXPECT_NE(access((out + "/summary.json").c_str(), F_OK), 0) << c.what << ": it ran";
  }
  std::remove(bad.c_str());
}

// A switch whose session cannot start (here the pack was damaged after
// start-up) ends nothing: the console goes back to the pack it left, runs
// out its time there and names the failure in summary.json.
TEST_F(Console, ASwitchThatCannotStartGoesBackToThePackItLeft) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  const std::string other = ::testing::TempDir() + "/console_c_" + std::to_string(getpid()) + ".vvp";
  ASSERT_TRUE(
      visvol::storage::build_pack(visvol::fields::testing::fractal(65, 9), small_pack_params(), "", other).ok());
  const std::string first_id = "console_" + std::to_string(getpid()),
                    other_id = "console_c_" + std::to_string(getpid());

  ParticipantConfig pc;
  pc.domain_id = 226;
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto commands = Writer::create(**participant, Topic::command);
  auto acks = Reader::create(**participant, Topic::command_ack);
  ASSERT_TRUE(commands.ok() && acks.ok());
  const std::string out = out_dir("switch_back");
  Outcome r;
  std::thread run([&] {
    r = console("--pack " + *pack_ + " --terrain " + other +
                " --seconds 6 --domain 226 --priority 0 --no-lock "
                "--segments 32 --script none --thumbnail-view none --out " +
                out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  ASSERT_TRUE(acks->wait_for_writers(1, 10.0).ok()) << "the console's acknowledgements never appeared";
  // the pack is cut short on disk after the console checked it
  ASSERT_EQ(truncate(other.c_str(), 8192), 0);
  Command go{};
  go.kind = CommandKind::switch_terrain;
  go.sequence = 3;
  copy_text(go.source, "console_test");
  copy_text(go.pack_id, other_id);
  CommandMessage msg;
  ASSERT_EQ(commands->write(&msg.fill(go)), DDS_RETCODE_OK);
  run.join();
  std::remove(other.c_str());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("switch-terrain failed; back on " + *pack_), std::string::npos) << r.err;

  const nlohmann::json before = nlohmann::json::parse(slurp(out + "/session-1-" + first_id + "/summary.json"));
  EXPECT_EQ(before["switched_to"], other_id);
  const nlohmann::json after = nlohmann::json::parse(slurp(out + "/summary.json"));
  EXPECT_EQ(after["pack_id"], first_id);
  EXPECT_EQ(after["session"], 2);
  const std::string failed = after["switch_failed"].get<std::string>();
  EXPECT_EQ(failed.rfind(other_id + ": ", 0), 0u) << failed;
  EXPECT_NE(failed.find("truncated"), std::string::npos) << failed;
  EXPECT_GT(after["loop"]["ticks"].get<int>(), 1000);  // it ran on after the failed switch
}

}  // namespace
