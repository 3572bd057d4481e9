// Crafted packs: checksums consistent, contents hostile. Every one must be
// refused by Pack::open (or, for tile contents, by verify) with a message
// naming the pack file and the problem, never crash a reader.
#include <gtest/gtest.h>
#include <unistd.h>

#include <climits>
#include <cmath>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "../fields/terrains.hpp"
#include "crafted_pack.hpp"
#include "fields/sampler.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "storage/pack_writer.hpp"

namespace visvol::storage {
namespace {

using testing::CraftedPack;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDenormal = std::numeric_limits<double>::denorm_min();

std::string temp_path(const std::string& stem) {
  return ::testing::TempDir() + "/" + stem + "_" + std::to_string(::getpid()) + ".vvp";
}

PackBuildParams small_params(VisibilityEncoding enc) {
  PackBuildParams p;
  p.field.nz = 16;
  p.field.ceiling_m = 100;
  p.field.range_posts = 6;
  p.lod_levels = 2;
  p.encoding = enc;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  return p;
}

// A valid two-level pack of each visibility encoding, built once.
class Crafted : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (const VisibilityEncoding enc : {VisibilityEncoding::uint16, VisibilityEncoding::float32}) {
      const std::string path = temp_path(enc == VisibilityEncoding::uint16 ? "crafted_u16" : "crafted_f32");
      ASSERT_TRUE(build_pack(fields::testing::fractal(70, 3), small_params(enc), R"({"path":"fractal"})", path).ok());
      paths_->push_back(path);
    }
  }
  static void TearDownTestSuite() {
    for (const std::string& p : *paths_) std::remove(p.c_str());
  }
  static const std::string& valid(VisibilityEncoding enc = VisibilityEncoding::uint16) {
    return (*paths_)[enc == VisibilityEncoding::uint16 ? 0 : 1];
  }

  struct Case {
    std::string what;
    std::function<void(CraftedPack&)> edit;
    std::string expect;  // in the message
  };
  // Each case crafted from the valid pack and refused at open, by name.
  static void expect_refused_at_open(const std::vector<Case>& cases) {
    const std::string bad = temp_path("crafted_bad");
    for (const Case& c : cases) {
      CraftedPack pack(valid());
      c.edit(pack);
      pack.write(bad);
      const Result<std::shared_ptr<const Pack>> opened = Pack::open(bad);
      ASSERT_FALSE(opened.ok()) << c.what << ": opened";
      EXPECT_EQ(opened.status().code(), Errc::corrupt) << c.what;
      const std::string& m = opened.status().message();
      EXPECT_EQ(m.rfind(bad + ": ", 0), 0u) << c.what << ": does not name the file: " << m;
      EXPECT_NE(m.find(c.expect), std::string::npos) << c.what << ": " << m;
    }
    std::remove(bad.c_str());
  }

  static std::vector<std::string>* paths_;
};
std::vector<std::string>* Crafted::paths_ = new std::vector<std::string>();

TEST_F(Crafted, TheValidPackOpensAndVerifies) {
  for (const VisibilityEncoding enc : {VisibilityEncoding::uint16, VisibilityEncoding::float32}) {
    const std::string copy = temp_path("crafted_copy");
    CraftedPack(valid(enc)).write(copy);  // rewriting the checksums alone changes nothing
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(copy);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    EXPECT_TRUE((*pack)->verify().ok());
    std::remove(copy.c_str());
  }
}

TEST_F(Crafted, NonFiniteAndOutOfRangeHeightsAreRefusedNamingThePost) {
  expect_refused_at_open({
      {"NaN post", [](CraftedPack& p) { p.set_height(0, 5, 7, NAN); }, "level 0: post (5, 7) has height nan"},
      {"infinite post", [](CraftedPack& p) { p.set_height(0, 66, 1, INFINITY); }, "height tile (1, 0) of level 0"},
      {"NaN on level 1", [](CraftedPack& p) { p.set_height(1, 3, 3, NAN); }, "of level 1: post (3, 3)"},
      {"huge post", [](CraftedPack& p) { p.set_height(0, 0, 0, 1e30f); }, "not a finite height within"},
      {"post far below", [](CraftedPack& p) { p.set_height(0, 9, 9, -5000.0f); }, "post (9, 9)"},
  });
}

TEST_F(Crafted, LevelGeometryOutsideSaneRangesIsRefused) {
  auto dz = [](double v) { return [v](CraftedPack& p) { p.level(0).dz_m = p.level(1).dz_m = v; }; };
  auto spacing = [](double v) { return [v](CraftedPack& p) { p.level(0).spacing_m = v; }; };
  expect_refused_at_open({
      {"denormal dz", dz(kDenormal), "level 0: voxel level spacing dz 4.9406564584124654e-324 m"},
      {"zero dz", dz(0), "level 0: voxel level spacing dz 0 m"},
      {"negative dz", dz(-2), "dz -2 m"},
      {"NaN dz", dz(kNaN), "dz nan m"},
      {"huge dz", dz(1e300), "dz 1.0000000000000001e+300 m"},
      {"denormal spacing", spacing(kDenormal), "level 0: post spacing 4.9406564584124654e-324 m"},
      {"zero spacing", spacing(0), "post spacing 0 m"},
      {"negative spacing", spacing(-30), "post spacing -30 m"},
      {"NaN spacing", spacing(kNaN), "post spacing nan m"},
      {"huge spacing", spacing(1e300), "post spacing 1.0000000000000001e+300 m"},
      {"NaN origin", [](CraftedPack& p) { p.level(0).origin_x = kNaN; }, "level 0: origin (nan, "},
      {"far origin", [](CraftedPack& p) { p.level(0).origin_y = 1e300; }, "origin"},
      {"NaN z0", [](CraftedPack& p) { p.level(0).z0_m = kNaN; }, "level 0: voxel levels from nan m"},
      {"top beyond range", [](CraftedPack& p) { p.level(0).z0_m = 199999; }, "not within +-200000 m or not rising"},
      {"negative range", [](CraftedPack& p) { p.level(0).range_posts = -1; }, "range of -1 posts"},
  });
}

TEST_F(Crafted, DimensionsThatOverflowAreRefused) {
  expect_refused_at_open({
      {"nx INT_MAX", [](CraftedPack& p) { p.level(0).nx = INT_MAX; }, "level 0: grid 2147483647 x"},
      {"ny negative", [](CraftedPack& p) { p.level(0).ny = -70; }, "level 0: grid 70 x -70"},
      {"nz INT_MIN", [](CraftedPack& p) { p.level(1).nz = INT_MIN; }, "level 1: grid"},
      {"tile count", [](CraftedPack& p) { p.header().tile_count = ~0ull / 8; }, "tile table"},
  });
}

TEST_F(Crafted, CoarserLevelsMustCoverTheFinerLevelsArea) {
  expect_refused_at_open({
      {"spacing", [](CraftedPack& p) { p.level(1).spacing_m *= 3; }, "level 1: spacing"},
      {"shifted", [](CraftedPack& p) { p.level(1).origin_x += 1000; }, "do not cover the finer level's area"},
      {"voxel levels", [](CraftedPack& p) { p.level(1).dz_m *= 2; }, "level 1: voxel levels"},
      {"lifted", [](CraftedPack& p) { p.level(1).z0_m += 50; }, "differ from the finer level's"},
      // one range in posts at every level, the one the build names
      {"range", [](CraftedPack& p) { p.level(1).range_posts = 32768; },
       "level 1: range of 32768 posts differs from the finer level's 6"},
  });
}

TEST_F(Crafted, ARangeOtherThanTheBuildNamedIsRefused) {
  auto in_build = [](const std::string& key, const nlohmann::json& value) {
    return [key, value](CraftedPack& p) {
      nlohmann::json j = nlohmann::json::parse(p.metadata());
      j["build"][key] = value;
      p.set_metadata(j.dump());
    };
  };
  auto both_levels = [](int range) {
    return [range](CraftedPack& p) { p.level(0).range_posts = p.level(1).range_posts = range; };
  };
  expect_refused_at_open({
      {"range 0", both_levels(0), "metadata build.range_posts 6 differs from level 0's range of 0 posts"},
      {"range 32768", both_levels(32768), "differs from level 0's range of 32768 posts"},
      {"build names another", in_build("range_posts", 7), "build.range_posts 7 differs"},
      {"shape none", in_build("range_shape", "none"), "build.range_posts 0 (range_shape none) differs"},
  });
}

TEST_F(Crafted, NonZeroReservedHeaderBytesAreRefused) {
  expect_refused_at_open({
      {"first", [](CraftedPack& p) { p.header().reserved[0] = 1; }, "reserved header byte 108 is 1, not 0"},
      {"last", [](CraftedPack& p) { p.header().reserved[sizeof p.header().reserved - 1] = 0xff; },
       "reserved header byte 4091 is 255"},
  });
}

TEST_F(Crafted, MetadataOfTheWrongTypesIsRefusedByMember) {
  auto member = [](const std::string& key, const nlohmann::json& value) {
    return [key, value](CraftedPack& p) {
      nlohmann::json j = nlohmann::json::parse(p.metadata());
      j[key] = value;
      p.set_metadata(j.dump());
    };
  };
  auto in_build = [](const std::string& key, const nlohmann::json& value) {
    return [key, value](CraftedPack& p) {
      nlohmann::json j = nlohmann::json::parse(p.metadata());
      j["build"][key] = value;
      p.set_metadata(j.dump());
    };
  };
  expect_refused_at_open({
      {"tool {}", member("tool", nlohmann::json::object()), "metadata tool is {}, not a string"},
      {"build []", member("build", nlohmann::json::array()), "metadata build is [], not an object"},
      {"source 5", member("source", 5), "metadata source is 5"},
      {"source.path", member("source", {{"path", {1, 2}}}), "metadata source.path is [1,2], not a string"},
      {"crs_wkt", member("crs_wkt", 7), "crs_wkt is 7"},
      {"crs_name null", member("crs_name", nullptr), "crs_name is null"},
      {"created_utc", member("created_utc", false), "created_utc is false"},
      {"geotransform", member("geotransform", {1, 2}), "geotransform is [1,2], not an array of 6"},
      {"levels", member("levels", {1}), "metadata levels[0] is not an object"},
      {"version", member("version", -1), "metadata version is -1, not a count"},
      {"curvature text", in_build("curvature_coeff", "x"), "metadata build.curvature_coeff is \"x\""},
      {"curvature 7", in_build("curvature_coeff", 7), "not a number in 0..1"},
      {"nz string", in_build("nz", "16"), "build.nz is \"16\", not a count"},
      {"weights", in_build("weights", 1), "build.weights is 1, not true or false"},
      {"range shape", in_build("range_shape", 1), "build.range_shape"},
      {"an array", [](CraftedPack& p) { p.set_metadata("[]"); }, "metadata is not a JSON object"},
      {"not JSON", [](CraftedPack& p) { p.set_metadata("{\"tool\": "); }, "metadata: not valid JSON"},
      {"NUL after it", [](CraftedPack& p) { p.set_metadata(p.metadata() + std::string(16, '\0')); },
       "metadata: not valid JSON: a NUL byte"},
      // printing or copying it would recurse once a level
      {"nested",
       [](CraftedPack& p) {
         p.set_metadata("{\"tool\": " + std::string(100000, '[') + std::string(100000, ']') + "}");
       },
       "metadata: JSON nested deeper than 64 levels"},
  });
}

TEST_F(Crafted, UnknownMetadataMembersAreLeftAlone) {
  const std::string path = temp_path("crafted_extra");
  CraftedPack p(valid());
  nlohmann::json j = nlohmann::json::parse(p.metadata());
  j["made_by_a_later_version"] = {{"anything", {1, "two"}}};
  j["build"]["a_later_parameter"] = "x";
  p.set_metadata(j.dump());
  p.write(path);
  const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  EXPECT_TRUE(pack.ok()) << pack.status().message();
  std::remove(path.c_str());
}

// float32 F_p is checked with the tile's checksum: verify and a level's
// reader refuse it, naming the tile and the voxel.
TEST_F(Crafted, NonFiniteFloatVisibilityFailsVerifyNamingTheVoxel) {
  const std::string path = temp_path("crafted_fp");
  for (const float f : {NAN, INFINITY, -0.5f, 1.5f}) {
    CraftedPack p(valid(VisibilityEncoding::float32));
    p.set_visibility(0, 17, 2, 3, f);
    p.write(path);
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
    ASSERT_TRUE(pack.ok()) << pack.status().message();  // open reads no F_p
    const Status st = (*pack)->verify();
    ASSERT_FALSE(st.ok()) << f;
    EXPECT_NE(st.message().find(path + ": visibility tile (1, 0) of level 0: F_p at voxel (17, 2, 3)"),
              std::string::npos)
        << st.message();
    EXPECT_FALSE(PackLevel::open(*pack, 0).ok());
    EXPECT_TRUE(PackLevel::open(*pack, 1).ok());
  }
  std::remove(path.c_str());
}

// Area factors are read only to be exported: verify and the export's reads
// refuse one that sqrt(1 + slope^2) cannot be (NaN, infinite, negative or
// steeper than the level's heights allow), naming the post (they passed
// verify and were exported as they were).
TEST_F(Crafted, AreaFactorsOutOfRangeFailVerifyNamingThePost) {
  const std::string path = temp_path("crafted_area");
  for (const float a : {NAN, INFINITY, -1.0f, 0.5f, 3.4e38f}) {
    CraftedPack p(valid(VisibilityEncoding::uint16));
    p.set_area(0, 5, 7, a);
    p.write(path);
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    const Status st = (*pack)->verify();
    ASSERT_FALSE(st.ok()) << a;
    EXPECT_NE(st.message().find(path + ": area tile (0, 0) of level 0: post (5, 7) has area factor"), std::string::npos)
        << st.message();
  }
  std::remove(path.c_str());
}

// Terrain force samples lie within the band's offset of the terrain (60 m
// here): one beyond it fails verify and the level's reader, naming the tile,
// the sample and the column (-327 m in a +-60 m band passed verify, plan and
// the console, whose rope wandered off).
TEST_F(Crafted, TerrainForceSamplesBeyondTheBandFailVerifyNamingTheSample) {
  const std::string path = temp_path("crafted_tff");
  for (const auto& [component, cm] : std::vector<std::pair<int, int>>{{0, -32768}, {2, 6200}, {3, 32767}}) {
    CraftedPack p(valid(VisibilityEncoding::uint16));
    p.set_tff(0, 18, 3, 5, component, static_cast<std::int16_t>(cm));
    p.write(path);
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    const Status st = (*pack)->verify();
    ASSERT_FALSE(st.ok()) << component << " " << cm;
    EXPECT_NE(st.message().find(path + ": terrain force tile (1, 0) of level 0: sample 5 of column (18, 3)"),
              std::string::npos)
        << st.message();
    EXPECT_NE(st.message().find("beyond the band's +-60 m"), std::string::npos) << st.message();
    EXPECT_FALSE(PackLevel::open(*pack, 0).ok());
  }
  std::remove(path.c_str());
}

// The writer refuses up front what the reader would refuse: no build ends
// in a pack that cannot be opened.
TEST(CraftedLayout, TheWriterRefusesWhatTheReaderWould) {
  LevelEntry e{};
  e.nx = 20;
  e.ny = 20;
  e.nz = 8;
  e.spacing_m = 30;
  e.dz_m = 5;
  PackLayout layout;
  layout.levels = {e};
  EXPECT_TRUE(validate(layout).ok());
  layout.levels[0].dz_m = kDenormal;
  const Status st = validate(layout);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("pack: level 0: voxel level spacing dz"), std::string::npos) << st.message();
  layout.levels[0].dz_m = 5;
  LevelEntry coarse = e;
  coarse.nx = coarse.ny = 10;
  coarse.spacing_m = 60;  // origin not moved half a post
  layout.levels.push_back(coarse);
  EXPECT_NE(validate(layout).message().find("level 1: spacing"), std::string::npos);
  PackLayout shifted = layout;
  shifted.levels[1].origin_x = 15;
  shifted.levels[1].origin_y = -15;
  EXPECT_TRUE(validate(shifted).ok()) << validate(shifted).message();
}

}  // namespace
}  // namespace visvol::storage
