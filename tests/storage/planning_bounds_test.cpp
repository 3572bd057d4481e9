// Planning bounds: the rule, what a pack build records, what the reader
// derives for packs built before bounds were recorded, and malformed metadata.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "../fields/terrains.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "storage/pack_writer.hpp"
#include "storage/planning_bounds.hpp"
#include "tests/storage/bare_pack.hpp"

namespace visvol::storage {
namespace {

using fields::RangeShape;
using testing::grid_40x30;
using testing::level_40x30;
using testing::write_bare_pack;

std::string temp_path(const std::string& stem) {
  return ::testing::TempDir() + "/bounds_" + stem + "_" + std::to_string(::getpid()) + ".vvp";
}

void expect_box(const fields::Bounds2D& b, double xmin, double ymin, double xmax, double ymax) {
  EXPECT_DOUBLE_EQ(b.xmin_m, xmin);
  EXPECT_DOUBLE_EQ(b.ymin_m, ymin);
  EXPECT_DOUBLE_EQ(b.xmax_m, xmax);
  EXPECT_DOUBLE_EQ(b.ymax_m, ymax);
}

TEST(PlanningBoundsRule, RangeMarginForCubeAndSphere) {
  for (RangeShape shape : {RangeShape::cube, RangeShape::sphere}) {
    const PlanningBounds b = planning_bounds_rule(grid_40x30(), shape, 8);
    EXPECT_DOUBLE_EQ(b.margin_m, 240.0);  // 8 posts of 30 m
    expect_box(b.box, 1240, 4370, 1930, 4760);
    EXPECT_FALSE(b.recorded);
  }
}

TEST(PlanningBoundsRule, UnrangedMarginIsAnEighthOfTheSmallerSide) {
  const PlanningBounds b = planning_bounds_rule(grid_40x30(), RangeShape::none, 0);
  EXPECT_DOUBLE_EQ(b.margin_m, 870.0 / 8.0);  // y spans 29 x 30 m
  expect_box(b.box, 1108.75, 4238.75, 2061.25, 4891.25);
}

TEST(PlanningBoundsRule, AGivenMarginOverridesEveryShape) {
  for (RangeShape shape : {RangeShape::cube, RangeShape::sphere, RangeShape::none}) {
    const PlanningBounds b = planning_bounds_rule(grid_40x30(), shape, 8, 100.0);
    EXPECT_DOUBLE_EQ(b.margin_m, 100.0);
    expect_box(b.box, 1100, 4230, 2070, 4900);
  }
  EXPECT_FALSE(planning_bounds_rule(grid_40x30(), RangeShape::cube, 8, 0.0).box.empty());
  // 435 m leaves nothing of the 870 m side
  EXPECT_TRUE(planning_bounds_rule(grid_40x30(), RangeShape::cube, 8, 435.0).box.empty());
}

TEST(PlanningBoundsRule, DescribedForPeopleInMetres) {
  EXPECT_EQ(describe(planning_bounds_rule(grid_40x30(), RangeShape::cube, 8)),
            "x 1240.00..1930.00, y 4370.00..4760.00 (margin 240 m)");
  EXPECT_EQ(describe(planning_bounds_rule(grid_40x30(), RangeShape::none, 0)),
            "x 1108.75..2061.25, y 4238.75..4891.25 (margin 108.75 m)");
  // to the centimetre, rounded inward: a point read off the text is inside
  EXPECT_EQ(describe(fields::Bounds2D{452918.0723, 5610000.004, 465068.0799, 5628000.0}),
            "x 452918.08..465068.07, y 5610000.01..5628000.00");
}

PackBuildParams small_params() {
  PackBuildParams p;
  p.field.nz = 16;
  p.field.ceiling_m = 100;
  p.field.range_posts = 6;
  p.lod_levels = 2;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 6;
  return p;
}

std::shared_ptr<const Pack> open_ok(const std::string& path) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  EXPECT_TRUE(pack.ok()) << pack.status().message();
  return pack.ok() ? *pack : nullptr;
}

// A 33 x 33 fractal of 30 m posts: posts span 960 m a side.
class BuiltPack : public ::testing::Test {
 protected:
  PlanningBounds build_and_read(const PackBuildParams& p) {
    PackBuildReport report;
    const Status st = build_pack(terrain_, p, "", path_, {}, &report);
    EXPECT_TRUE(st.ok()) << st.message();
    const std::shared_ptr<const Pack> pack = open_ok(path_);
    if (!pack) return {};
    const PlanningBounds& read = pack->metadata().planning;
    EXPECT_TRUE(read.recorded);
    EXPECT_DOUBLE_EQ(read.margin_m, report.planning.margin_m);
    const fields::Bounds2D b = planning_bounds(*pack);
    expect_box(b, report.planning.box.xmin_m, report.planning.box.ymin_m, report.planning.box.xmax_m,
               report.planning.box.ymax_m);
    // recorded exactly as the rule derives it from level 0
    const PlanningBounds rule =
        planning_bounds_rule(pack->geometry(0), p.field.range_shape, p.field.range_posts, p.planning_margin_m);
    expect_box(b, rule.box.xmin_m, rule.box.ymin_m, rule.box.xmax_m, rule.box.ymax_m);
    const nlohmann::json meta = nlohmann::json::parse(pack->metadata().json);
    for (const char* key : {"xmin_m", "ymin_m", "xmax_m", "ymax_m", "margin_m"}) {
      EXPECT_TRUE(meta["planning_bounds"][key].is_number()) << key;
    }
    return read;
  }
  void TearDown() override { std::remove(path_.c_str()); }

  const fields::Heightfield terrain_ = fields::testing::fractal(33, 2);
  const std::string path_ = temp_path("built");
};

TEST_F(BuiltPack, RecordsTheRangeMargin) {
  const PlanningBounds b = build_and_read(small_params());
  EXPECT_DOUBLE_EQ(b.margin_m, 180.0);  // 6 posts of 30 m
  const double x0 = terrain_.x_of(0), y0 = terrain_.y_of(0);
  expect_box(b.box, x0 + 180, y0 - 960 + 180, x0 + 960 - 180, y0 - 180);
}

TEST_F(BuiltPack, RecordsAGivenMarginOverTheRange) {
  PackBuildParams p = small_params();
  p.planning_margin_m = 45.5;
  EXPECT_DOUBLE_EQ(build_and_read(p).margin_m, 45.5);
}

TEST_F(BuiltPack, UnrangedFieldGetsAnEighthOfTheDemOrTheGivenMargin) {
  PackBuildParams p = small_params();
  p.field.range_shape = RangeShape::none;
  EXPECT_DOUBLE_EQ(build_and_read(p).margin_m, 120.0);  // 960 m / 8
  p.planning_margin_m = 300.0;
  EXPECT_DOUBLE_EQ(build_and_read(p).margin_m, 300.0);
}

TEST_F(BuiltPack, RefusesEmptyBoundsAndBadMarginsBeforeWriting) {
  PackBuildParams p = small_params();
  p.field.range_posts = 16;  // 480 m: half of the 960 m of posts
  Status st = build_pack(terrain_, p, "", path_);
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find("960 x 960 m"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("--planning-margin"), std::string::npos) << st.message();
  // a smaller margin makes the same field plannable
  p.planning_margin_m = 400.0;
  EXPECT_TRUE(build_pack(terrain_, p, "", path_).ok());
  std::remove(path_.c_str());
  for (double bad : {-1.0, std::nan(""), HUGE_VAL, 480.0}) {
    p.planning_margin_m = bad;
    st = build_pack(terrain_, p, "", path_);
    EXPECT_EQ(st.code(), Errc::invalid_argument) << bad;
    EXPECT_NE(st.message().find("--planning-margin"), std::string::npos) << st.message();
    EXPECT_NE(access(path_.c_str(), F_OK), 0) << bad;
  }
}

PlanningBounds read_planning(const std::string& path) {
  const std::shared_ptr<const Pack> pack = open_ok(path);
  std::remove(path.c_str());
  return pack ? pack->metadata().planning : PlanningBounds{};
}

TEST(OlderPack, BoundsAreDerivedFromLevelZeroAndTheRangeShape) {
  for (const char* shape : {"cube", "sphere"}) {
    const PlanningBounds b = read_planning(write_bare_pack(temp_path("old_range"), level_40x30(8),
                                                           nlohmann::json{{"build", {{"range_shape", shape}}}}.dump()));
    EXPECT_FALSE(b.recorded);
    EXPECT_DOUBLE_EQ(b.margin_m, 240.0) << shape;
    expect_box(b.box, 1240, 4370, 1930, 4760);
  }
  const PlanningBounds none =
      read_planning(write_bare_pack(temp_path("old_none"), level_40x30(0), R"({"build": {"range_shape": "none"}})"));
  EXPECT_FALSE(none.recorded);
  EXPECT_DOUBLE_EQ(none.margin_m, 108.75);
}

TEST(OlderPack, WithoutBuildParametersTheLevelsRangeDecides) {
  EXPECT_DOUBLE_EQ(read_planning(write_bare_pack(temp_path("old_bare"), level_40x30(8), "{}")).margin_m, 240.0);
  EXPECT_DOUBLE_EQ(read_planning(write_bare_pack(temp_path("old_bare0"), level_40x30(0), "{}")).margin_m, 108.75);
}

TEST(OlderPack, TooSmallForItsRangeOpensWithEmptyBounds) {
  // 15 posts of range leave nothing of 29 x 30 m: readable, but nowhere to plan
  const std::string path =
      write_bare_pack(temp_path("old_small"), level_40x30(15), R"({"build": {"range_shape": "cube"}})");
  const std::shared_ptr<const Pack> pack = open_ok(path);
  std::remove(path.c_str());
  ASSERT_TRUE(pack);
  EXPECT_TRUE(planning_bounds(*pack).empty());
  EXPECT_FALSE(pack->metadata().planning.recorded);
  // what every planner, checker and console asks before it trusts a path there
  const Status none = check_planning_bounds(*pack);
  EXPECT_EQ(none.code(), Errc::invalid_argument);
  EXPECT_NE(none.message().find(path + ": no planning bounds"), std::string::npos) << none.message();
  const std::string wide = write_bare_pack(temp_path("old_wide"), level_40x30(8), "{}");
  const std::shared_ptr<const Pack> plannable = open_ok(wide);
  std::remove(wide.c_str());
  ASSERT_TRUE(plannable);
  EXPECT_TRUE(check_planning_bounds(*plannable).ok());
}

TEST(RecordedPack, BoundsAreReadAsRecorded) {
  const std::string meta =
      R"({"build": {"range_shape": "cube"}, "planning_bounds":
          {"xmin_m": 1300, "ymin_m": 4400.5, "xmax_m": 1900, "ymax_m": 4700, "margin_m": 255}})";
  const PlanningBounds b = read_planning(write_bare_pack(temp_path("recorded"), level_40x30(8), meta));
  EXPECT_TRUE(b.recorded);
  EXPECT_DOUBLE_EQ(b.margin_m, 255);
  expect_box(b.box, 1300, 4400.5, 1900, 4700);
}

// Malformed values fail Pack::open as corrupt, naming what is wrong.
void expect_refused(const std::string& metadata, const std::string& named) {
  const std::string path = write_bare_pack(temp_path("malformed"), level_40x30(8), metadata);
  const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  std::remove(path.c_str());
  ASSERT_FALSE(pack.ok()) << metadata;
  EXPECT_EQ(pack.status().code(), Errc::corrupt) << metadata;
  EXPECT_NE(pack.status().message().find(named), std::string::npos) << pack.status().message();
}

std::string bounds_json(const std::string& xmin, const std::string& margin = "240", const std::string& xmax = "1930") {
  return R"({"planning_bounds": {"xmin_m": )" + xmin + R"(, "ymin_m": 4370, "xmax_m": )" + xmax +
         R"(, "ymax_m": 4760, "margin_m": )" + margin + "}}";
}

TEST(RecordedPack, MalformedBoundsFailOpenByName) {
  expect_refused(bounds_json("\"1240\""), "xmin_m");
  expect_refused(bounds_json("null"), "xmin_m");  // how JSON writers store NaN
  expect_refused(bounds_json("[1240]"), "xmin_m");
  expect_refused(bounds_json("1e400"), "not valid JSON");  // the parser refuses infinities
  expect_refused(bounds_json("1240", "-1"), "margin_m");
  expect_refused(bounds_json("1240", "true"), "margin_m");
  expect_refused(bounds_json("1940"), "empty");
  expect_refused(bounds_json("900"), "outside level 0");
  expect_refused(bounds_json("1240", "240", "3000"), "outside level 0");
  expect_refused(R"({"planning_bounds": {"xmin_m": 1240, "ymin_m": 4370, "xmax_m": 1930, "ymax_m": 4760}})",
                 "margin_m is missing");
  expect_refused(R"({"planning_bounds": [1240, 4370, 1930, 4760]})", "not a JSON object");
  expect_refused(R"({"planning_bounds": "everywhere"})", "not a JSON object");
}

TEST(OlderPack, MalformedRangeShapeFailsOpenByName) {
  expect_refused(R"({"build": {"range_shape": "cone"}})", "build.range_shape");
  expect_refused(R"({"build": {"range_shape": 1}})", "build.range_shape");
  // a ranged shape with no range in level 0
  const std::string path =
      write_bare_pack(temp_path("norange"), level_40x30(0), R"({"build": {"range_shape": "cube"}})");
  const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  std::remove(path.c_str());
  ASSERT_FALSE(pack.ok());
  EXPECT_NE(pack.status().message().find("range of 0 posts"), std::string::npos) << pack.status().message();
}

}  // namespace
}  // namespace visvol::storage
