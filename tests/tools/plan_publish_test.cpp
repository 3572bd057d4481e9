// `visvol plan --publish`: the planner's path reaches a DDS subscriber as the
// console would publish it (domain 218, loopback), and the pieces it is made of.
#include "tools/visvol/plan_publish.hpp"

#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>

#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"
#include "drivers/dds/participant.hpp"

namespace {

using visvol::cli::subsample_indices;
using visvol::test::Outcome;
using visvol::test::slurp;
using visvol::test::visvol;

constexpr std::uint32_t kDomain = 218;

TEST(PlanPublish, SubsampleKeepsBothEndsEvenlySpaced) {
  const std::vector<int> all = subsample_indices(129, 512);
  ASSERT_EQ(all.size(), 129u);
  for (int i = 0; i < 129; ++i) EXPECT_EQ(all[static_cast<std::size_t>(i)], i);
  const std::vector<int> some = subsample_indices(1001, 512);
  ASSERT_EQ(some.size(), 512u);
  EXPECT_EQ(some.front(), 0);
  EXPECT_EQ(some.back(), 1000);
  for (std::size_t k = 1; k < some.size(); ++k) {
    const int gap = some[k] - some[k - 1];
    EXPECT_TRUE(gap == 1 || gap == 2 || gap == 3) << k << ": " << gap;
  }
}

class PlanPublishCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pack_ = new std::string(::testing::TempDir() + "/publish_" + std::to_string(getpid()) + ".vvp");
    const Outcome r = visvol("build " + visvol::test::kDem + " " + visvol::test::kSmallPackOptions + " -o " + *pack_);
    ASSERT_EQ(r.status, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::remove(pack_->c_str());
    delete pack_;
  }
  static std::string* pack_;
};
std::string* PlanPublishCli::pack_ = nullptr;

TEST_F(PlanPublishCli, SubscriberGetsTheFinalPathAndTheTerrain) {
  using namespace visvol::dds;
  using namespace visvol::msg;
  ParticipantConfig config;
  config.domain_id = kDomain;
  config.cyclone_xml = std::string(loopback_config());
  auto participant = Participant::create(config);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto paths = Reader::create(**participant, Topic::path_update);
  auto terrain = Reader::create(**participant, Topic::terrain);
  auto nav_path = Reader::create(**participant, Topic::path);  // as a ROS 2 node (RViz) subscribes
  ASSERT_TRUE(paths.ok() && terrain.ok() && nav_path.ok());

  // 600 segments: more vertices than a path sample holds (512)
  const std::string base = *pack_ + "_pub";
  const Outcome r = visvol("plan " + *pack_ +
                           " --from 550300 4182450 150 --to 550850 4181850 150 --objective hide --vehicle multirotor"
                           " --init straight --model spring --segments 600 --max-seconds 1 --json"
                           " --publish --domain " +
                           std::to_string(kDomain) + " -o " + base);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  ASSERT_TRUE(summary.contains("dds")) << r.out;
  EXPECT_GE(summary["dds"]["subscribers"].get<int>(), 2) << "PathUpdate and nav_msgs/Path readers";
  EXPECT_GE(summary["dds"]["nav_msgs_path_subscribers"].get<int>(), 1);
  EXPECT_TRUE(summary["dds"]["delivered"].get<bool>());
  EXPECT_EQ(summary["dds"]["publish_errors"].get<int>(), 0);

  // the reader keeps the latest (history 1): the final path
  int received = 0;
  auto taken = paths->take<visvol_msgs_msg_dds__PathUpdate_>(
      [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
        ++received;
        EXPECT_EQ(m.sequence_number, summary["dds"]["paths_published"].get<std::uint64_t>());
        EXPECT_EQ(m.converged, summary["converged"].get<bool>());
        // inside the envelope as the check found it, and only when no vertex was dropped
        bool limits_met = true;
        for (const nlohmann::json& l : summary["envelope"]) limits_met = limits_met && l["met"].get<bool>();
        EXPECT_EQ(m.inside_envelope, limits_met && summary["vertices"].get<int>() <= 512) << summary["envelope"].dump();
        EXPECT_STREQ(m.pack_id, ("publish_" + std::to_string(getpid())).c_str());
        EXPECT_EQ(m.objective, 1);  // hide
        EXPECT_NEAR(m.f_c, summary["fc_end"].get<double>(), 1e-9);
        EXPECT_NEAR(m.length_m, summary["length_m"].get<double>(), 1e-6);
        EXPECT_NEAR(m.min_clearance_m, summary["min_clearance_m"].get<double>(), 1e-9);
        // the answer's vertices (the rope's 601 or a fitted start's), at most 512 of them, ends kept
        const std::uint32_t n = std::min<std::uint32_t>(512u, summary["vertices"].get<std::uint32_t>());
        ASSERT_EQ(m.positions_m._length, n);
        ASSERT_EQ(m.visibility._length, n);
        ASSERT_EQ(m.clearance_m._length, n);
        EXPECT_NEAR(m.positions_m._buffer[0].x, 550300, 1e-6);
        EXPECT_NEAR(m.positions_m._buffer[0].y, 4182450, 1e-6);
        EXPECT_NEAR(m.positions_m._buffer[n - 1].x, 550850, 1e-6);
        EXPECT_NEAR(m.positions_m._buffer[n - 1].z, 150, 1e-6);
        for (std::uint32_t i = 0; i < n; ++i) {
          EXPECT_GE(m.visibility._buffer[i], 0.0);
          EXPECT_LE(m.visibility._buffer[i], 1.0);
          EXPECT_GE(m.clearance_m._buffer[i], m.min_clearance_m - 1.0);
        }
      });
  ASSERT_TRUE(taken.ok());
  EXPECT_EQ(received, 1);

  int terrains = 0;
  auto t = terrain->take<visvol_msgs_msg_dds__TerrainInfo_>(
      [&](const visvol_msgs_msg_dds__TerrainInfo_& m, const dds_sample_info_t&) {
        ++terrains;
        EXPECT_STREQ(m.crs, "EPSG:26710");  // the quad is NAD27 / UTM 10N
        EXPECT_NEAR(m.post_spacing_m, 30.0, 1e-9);
        EXPECT_LE(m.min_m.x, 550300);
        EXPECT_GE(m.max_m.x, 550850);
        // the planning bounds, inside the pack, around the ends
        EXPECT_GT(m.planning_min_m.x, m.min_m.x);
        EXPECT_LT(m.planning_max_m.y, m.max_m.y);
        EXPECT_LE(m.planning_min_m.x, 550300);
        EXPECT_GE(m.planning_max_m.x, 550850);
      });
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(terrains, 1);
  for (const char* ext : {".geojson", ".csv", ".kml", ".plan"}) std::remove((base + ext).c_str());
}

TEST_F(PlanPublishCli, BadPublishOptionsExitTwoWithOneLine) {
  const std::string ends = " --from 550300 4182450 150 --to 550850 4181850 150 --objective hide --vehicle multirotor";
  for (const std::string& extra :
       {std::string(" --publish --domain 400"), std::string(" --publish --dds-config /nonexistent.xml"),
        std::string(" --publish --publish-hz 0"), std::string(" --publish --linger -1"),
        // checked without --publish too: a value typed is a value meant
        std::string(" --publish-hz nan"), std::string(" --linger inf")}) {
    const Outcome r = visvol("plan " + *pack_ + ends + extra + " -o " + *pack_ + "_never");
    EXPECT_EQ(r.status, 2) << extra << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << extra << ": " << r.err;
  }
  // -o names a base: /dev/null made /dev/null.csv and its siblings in /dev
  const Outcome device = visvol("plan " + *pack_ + ends + " -o /dev/null");
  EXPECT_EQ(device.status, 2);
  EXPECT_NE(device.err.find("/dev/null is not a regular file: -o names the outputs' base"), std::string::npos)
      << device.err;
  EXPECT_NE(access("/dev/null.csv", F_OK), 0);
  // /dev/stderr is a regular file when stderr is one: /dev/stderr.csv and its siblings
  const Outcome in_dev = visvol::test::run_command("sh -c '" + std::string(VISVOL_BIN) + " plan " + *pack_ + ends +
                                                   " -o /dev/stderr 2>" + *pack_ + "_err.txt'");
  EXPECT_EQ(in_dev.status, 2);
  EXPECT_NE(slurp(*pack_ + "_err.txt").find("a system folder"), std::string::npos) << slurp(*pack_ + "_err.txt");
  std::remove((*pack_ + "_err.txt").c_str());
  EXPECT_NE(access("/dev/stderr.csv", F_OK), 0);
  const Outcome folder = visvol("plan " + *pack_ + ends + " -o " + ::testing::TempDir());
  EXPECT_EQ(folder.status, 2);
  EXPECT_NE(folder.err.find("is a directory: -o names the outputs' base"), std::string::npos) << folder.err;
}

}  // namespace
