// visvol-console's DDS side, seen from another participant (loopback): its
// paths, health and acknowledgements, and hostile commands to the end of a session.
#include "console_fixture.hpp"

namespace {

using namespace visvol::app::console_process_test;

TEST_F(Console, PublishesOnDdsAndTakesCommands) {
  using namespace visvol::dds;
  using namespace visvol::msg;
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
    r = console("--pack " + *pack_ +
                " --seconds 4 --domain 223 --priority 0 --no-lock --segments 32 --script none --out " + out);
  });
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  // the intake acknowledges at once: its ack writer must reach us first
  ASSERT_TRUE(acks->wait_for_writers(1, 10.0).ok()) << "the console's acknowledgements never appeared";
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
  // and from two more points beside it, visible to one, under a ceiling
  Command hide{};
  hide.kind = CommandKind::set_constraints;
  hide.sequence = 8;
  copy_text(hide.source, "console_test");
  auto at = [&](ConstraintKind kind, int i, int j, double up_m) {
    hide.constraints.items[hide.constraints.count++] = {
        kind, {g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, level->post(i, j) + up_m}, 0.0};
  };
  at(ConstraintKind::hidden_from, ci, cj, 50.0);
  at(ConstraintKind::hidden_from, ci - 20, cj + 10, 10.0);
  at(ConstraintKind::hidden_from, ci + 20, cj - 10, 10.0);
  at(ConstraintKind::visible_to, ci, cj + 30, 80.0);
  hide.constraints.items[hide.constraints.count++] = {ConstraintKind::max_agl, {}, 250.0};
  ASSERT_EQ(commands->write(&msg.fill(hide)), DDS_RETCODE_OK);
  // a ceiling under the clearance the command sets: the intake refuses it
  Command low{};
  low.kind = CommandKind::set_constraints;
  low.sequence = 9;
  copy_text(low.source, "console_test");
  low.constraints.count = 2;
  low.constraints.items[0] = {ConstraintKind::clearance, {}, 40.0};
  low.constraints.items[1] = {ConstraintKind::max_agl, {}, 35.0};
  ASSERT_EQ(commands->write(&msg.fill(low)), DDS_RETCODE_OK);
  run.join();
  ASSERT_EQ(r.status, 0) << r.err;

  int applied = 0, accepted = 0, rejected = 0;
  auto a = acks->take<visvol_msgs_msg_dds__CommandAck_>(
      [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
        const CommandAck ack = decode_ack(m);
        EXPECT_TRUE(ack.sequence >= 7u && ack.sequence <= 9u) << ack.sequence;
        applied += ack.result == AckResult::applied;
        accepted += ack.result == AckResult::accepted;
        if (ack.sequence == 9u) {
          rejected += ack.result == AckResult::rejected;
          EXPECT_NE(std::string(ack.reason).find("max-agl 35 m is not above the clearance 40 m"), std::string::npos)
              << ack.reason;
        }
      },
      16);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(accepted, 2);
  EXPECT_EQ(applied, 2);
  EXPECT_EQ(rejected, 1);
  int received = 0, flyable = 0;
  auto p = paths->take<visvol_msgs_msg_dds__PathUpdate_>(
      [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
        ++received;
        // the rope's 33 vertices fitted into the envelope (a segment split
        // where the terrain between vertices asks for it)
        EXPECT_GE(m.positions_m._length, 2u);
        EXPECT_LE(m.positions_m._length, 512u);
        EXPECT_EQ(m.objective, 2);  // show, after the command
        flyable += m.inside_envelope;
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
  // paths go out as the fitter keeps up (about 50 a second here; a loaded,
  // sanitized machine fits fewer): many, not one
  EXPECT_GT(s["dds"]["paths"].get<int>(), 10);
  // each update says whether its fit held the envelope: all did, or none did
  const nlohmann::json& fit = s["path"]["flyable"];
  if (fit["sent_outside_envelope"].get<int>() == 0) {
    EXPECT_EQ(flyable, received);
  }
  if (fit["sent_outside_envelope"].get<int>() == fit["sent"].get<int>()) {
    EXPECT_EQ(flyable, 0);
  }
  EXPECT_EQ(s["commands"]["applied"].get<int>(), 2);
  // the hulls were built beside the loop and put in force, with the ceiling
  const nlohmann::json& k = s["constraints"];
  EXPECT_EQ(k["built"].get<int>(), 1);
  EXPECT_EQ(k["sets_in_force"].get<int>(), 1);
  EXPECT_EQ(k["refused"].get<int>(), 0);
  EXPECT_EQ(k["max_observers"].get<int>(), 512);  // a small pack: the folded hulls fit in a quarter of the budget
  EXPECT_EQ(k["hidden_from"].size(), 3u);
  EXPECT_EQ(k["visible_to"].size(), 1u);
  EXPECT_EQ(k["max_agl_m"].get<double>(), 250.0);
  EXPECT_TRUE(k["max_altitude_m"].is_null());
  // and the final path checked against each of them
  ASSERT_EQ(s["check"]["constraints"].size(), 4u);
  EXPECT_EQ(s["check"]["constraints"][2]["kind"], "hidden-from");
  EXPECT_EQ(s["check"]["constraints"][3]["kind"], "visible-to");
  EXPECT_TRUE(s["check"]["all_met"].is_boolean());
}

// The red team's commands (issue 14), sent as an operator's tool would over
// DDS to a running console. Refused, each with a reason: ends 1 m apart (once
// a SIGSEGV), coincident, not finite, off the pack; absurd stiffness, segment
// counts and weights. Accepted, and applied or failed with a reason: the
// extremes the intake allows (ends just far enough apart, the largest weights
// and stiffness, every segment reserved, ends at the pack's corners and top,
// a model switch). The console runs to the end, its rope never stops being
// finite, and the last good command is applied.
TEST_F(Console, SurvivesHostileCommandsToTheEndOfItsSession) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  ParticipantConfig pc;
  pc.domain_id = 224;
  pc.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(pc);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto acks = Reader::create(**participant, Topic::command_ack);
  auto commands = Writer::create(**participant, Topic::command);
  ASSERT_TRUE(acks.ok() && commands.ok());

  const std::string out = out_dir("hostile");
  Outcome r;
  std::thread run([&] {
    r = console_limited("--pack " + *pack_ +
                        " --seconds 4 --domain 224 --priority 0 --no-lock --segments 32 --max-segments 128"
                        " --script none --thumbnail-view none --out " +
                        out);
  });
  struct Join {
    std::thread& t;
    ~Join() {
      if (t.joinable()) t.join();  // an ASSERT below must not destroy a running thread
    }
  } join{run};
  ASSERT_TRUE(commands->wait_for_readers(1, 10.0).ok()) << "the console's command intake never appeared";
  ASSERT_TRUE(acks->wait_for_writers(1, 10.0).ok()) << "the console's acknowledgements never appeared";

  const double nan = std::nan("");
  const std::vector<double> a = post(20, 20, 100), b = post(70, 70, 100);
  auto ends = [](const std::vector<double>& p, const std::vector<double>& q) {
    Command c{};
    c.kind = CommandKind::set_endpoints;
    c.endpoints.start = {p[0], p[1], p[2]};
    c.endpoints.end = {q[0], q[1], q[2]};
    return c;
  };
  std::vector<Command> hostile;
  hostile.push_back(ends(a, {a[0] + 1.0, a[1], a[2]}));  // 1 m apart, 32 segments
  hostile.push_back(ends(a, a));                         // coincident
  hostile.push_back(ends({nan, a[1], a[2]}, b));
  hostile.push_back(ends(a, {b[0] + 1e7, b[1], b[2]}));  // 10 000 km off the pack
  hostile.push_back(ends(a, {b[0], b[1], -1e300}));
  Command stiff{};
  stiff.kind = CommandKind::set_stiffness;
  stiff.stiffness = {-5.0, 1.0};
  hostile.push_back(stiff);
  stiff.stiffness = {nan, 1e308};
  hostile.push_back(stiff);
  Command segments{};
  segments.kind = CommandKind::set_segment_count;
  segments.segment_count = 4000000000u;
  hostile.push_back(segments);
  Command weights{};
  weights.kind = CommandKind::set_weights;
  weights.weights = {std::numeric_limits<double>::infinity(), 1.0, 1.0, 1.0};
  hostile.push_back(weights);
  // accepted by the intake: the extremes it allows
  auto pack = visvol::storage::Pack::open(*pack_);
  ASSERT_TRUE(pack.ok());
  auto level = visvol::storage::PackLevel::open(*pack, 0);
  ASSERT_TRUE(level.ok());
  const visvol::fields::VolumeGeometry g = level->geometry();
  const double top = g.z0_m + (g.nz - 1) * g.dz_m;
  std::vector<Command> extreme;
  std::vector<AckResult> expected;                        // what the executive answers each
  extreme.push_back(ends(a, {a[0] + 16.5, a[1], a[2]}));  // 32 segments of 0.52 m
  expected.push_back(AckResult::applied);
  Command heavy{};
  heavy.kind = CommandKind::set_weights;
  heavy.weights = {1e6, 1e6, 1e6, 1e6};
  extreme.push_back(heavy);
  expected.push_back(AckResult::failed);  // the pull would move a vertex kilometres a tick
  Command stiffest{};
  stiffest.kind = CommandKind::set_stiffness;
  stiffest.stiffness = {1e6, 1e6};
  extreme.push_back(stiffest);
  expected.push_back(AckResult::failed);  // half-metre capsules that stiff ring at 2 kHz
  Command every{};
  every.kind = CommandKind::set_segment_count;
  every.segment_count = 128;
  extreme.push_back(every);
  expected.push_back(AckResult::failed);  // 13 cm segments: under the half metre a segment needs
  // corner to corner of the planning bounds (the pack less the 8-post range), at the field's top
  const int in = 9;
  extreme.push_back(
      ends({g.origin_x + in * g.spacing_m, g.origin_y - in * g.spacing_m, top},
           {g.origin_x + (g.nx - 1 - in) * g.spacing_m, g.origin_y - (g.ny - 1 - in) * g.spacing_m, top}));
  expected.push_back(AckResult::applied);
  Command spring{};
  spring.kind = CommandKind::set_model;
  spring.model = RopeModel::spring_mass;
  extreme.push_back(spring);
  expected.push_back(AckResult::applied);
  Command calm = heavy;
  calm.weights = {1.0, 1.0, 1.0, 1.0};
  extreme.push_back(calm);
  expected.push_back(AckResult::applied);

  std::uint64_t seq = 100;
  CommandMessage msg;
  for (Command& c : hostile) {
    c.sequence = seq++;
    copy_text(c.source, "red_team");
    ASSERT_EQ(commands->write(&msg.fill(c)), DDS_RETCODE_OK);
  }
  const std::uint64_t first_extreme = seq;
  for (Command& c : extreme) {
    c.sequence = seq++;
    copy_text(c.source, "red_team");
    ASSERT_EQ(commands->write(&msg.fill(c)), DDS_RETCODE_OK);
    std::this_thread::sleep_for(std::chrono::milliseconds(150));  // a few hundred ticks of each
  }
  Command good = ends(a, b);
  good.sequence = seq;
  copy_text(good.source, "red_team");
  ASSERT_EQ(commands->write(&msg.fill(good)), DDS_RETCODE_OK);
  run.join();
  ASSERT_EQ(r.status, 0) << r.err;

  // the last answer to each command: rejected by the intake, or accepted and
  // then applied or failed by the executive
  std::map<std::uint64_t, CommandAck> last;
  auto taken = acks->take<visvol_msgs_msg_dds__CommandAck_>(
      [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
        const CommandAck ack = decode_ack(m);
        auto it = last.find(ack.sequence);
        if (it == last.end() || ack.result != AckResult::accepted) last[ack.sequence] = ack;
      },
      64);
  ASSERT_TRUE(taken.ok());
  for (std::uint64_t s = 100; s < first_extreme; ++s) {
    ASSERT_EQ(last.count(s), 1u) << "command " << s << " was never answered";
    const CommandAck& ack = last[s];
    EXPECT_TRUE(ack.result == AckResult::rejected || ack.result == AckResult::failed)
        << "command " << s << " ended " << static_cast<int>(ack.result);
    EXPECT_GT(std::string(ack.reason).size(), 5u) << "command " << s << " was refused without a reason";
  }
  for (std::uint64_t s = first_extreme; s < seq; ++s) {
    ASSERT_EQ(last.count(s), 1u) << "command " << s << " was never answered";
    const CommandAck& ack = last[s];
    EXPECT_EQ(ack.result, expected[static_cast<std::size_t>(s - first_extreme)])
        << "command " << s << " (accepted by the intake): " << ack.reason;
    if (ack.result == AckResult::failed) {
      EXPECT_GT(std::string(ack.reason).size(), 5u) << "command " << s;
    }
  }

  ASSERT_EQ(last.count(seq), 1u);
  EXPECT_EQ(last[seq].result, AckResult::applied) << last[seq].reason;

  const nlohmann::json s = nlohmann::json::parse(slurp(out + "/summary.json"));
  const int sent = static_cast<int>(hostile.size() + extreme.size()) + 1;
  EXPECT_GE(s["commands"]["applied"].get<int>(), 1);
  EXPECT_EQ(s["commands"]["intake"]["received"].get<int>(), sent);
  EXPECT_EQ(s["commands"]["failed"].get<int>() + s["commands"]["applied"].get<int>() +
                s["commands"]["intake"]["rejected"].get<int>(),
            sent);
  // nothing left a rope that stopped being finite (JSON writes NaN as null)
  EXPECT_EQ(s["path"]["rope_resets"].get<int>(), 0);
  EXPECT_TRUE(s["path"]["length_m"].is_number_float() && s["path"]["fc_end"].is_number_float()) << s["path"].dump();
}

}  // namespace
