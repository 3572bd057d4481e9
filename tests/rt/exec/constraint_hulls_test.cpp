// The hull builder beside the loop: what it builds is point_hull's, the
// newest request wins, a refused point leaves the set in force, and a set the
// loop holds is never rewritten under it.
#include "rt/exec/constraint_hulls.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "../../fields/terrains.hpp"
#include "fields/hull_kernel.hpp"
#include "storage/pack_build.hpp"

namespace visvol::rt {
namespace {

class ConstraintHullsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string("hulls_" + std::to_string(::getpid()) + ".vvp");
    storage::PackBuildParams p;
    p.field.nz = 16;
    p.field.ceiling_m = 200;
    p.field.range_posts = 8;
    p.lod_levels = 2;
    p.tff.band_offset_m = 60;
    p.tff.band_levels = 8;
    ASSERT_TRUE(storage::build_pack(fields::testing::fractal(65, 3), p, "", *path_).ok());
  }
  static void TearDownTestSuite() {
    std::remove(path_->c_str());
    delete path_;
  }
  void SetUp() override {
    auto pack = storage::Pack::open(*path_);
    ASSERT_TRUE(pack.ok());
    auto r = storage::ResidentPack::create(*pack, storage::ResidentConfig{});
    ASSERT_TRUE(r.ok()) << r.status().message();
    field_ = std::move(*r);
    hulls_ = ConstraintHulls::create(field_->level(0));
    hulls_->start();
  }

  // A post's position, `up_m` above (negative: below) its height.
  HullRequest hidden_from_post(int i, int j, double up_m, std::uint64_t sequence) const {
    const storage::ResidentLevel& l = field_->level(0);
    const fields::VolumeGeometry& g = l.geometry();
    HullRequest r;
    r.sequence = sequence;
    r.hidden = true;
    r.hidden_from_m[0] = g.origin_x + i * g.spacing_m;
    r.hidden_from_m[1] = g.origin_y - j * g.spacing_m;
    r.hidden_from_m[2] = l.post(i, j) + up_m;
    return r;
  }

  // What the loop would take within `seconds`, or null.
  const HullSet* wait_for_set(double seconds = 20.0) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (const HullSet* s = hulls_->take()) return s;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return nullptr;
  }

  static std::string* path_;
  std::unique_ptr<storage::ResidentPack> field_;
  std::unique_ptr<ConstraintHulls> hulls_;
};
std::string* ConstraintHullsTest::path_ = nullptr;

TEST_F(ConstraintHullsTest, BuildsWhatPointHullBuildsAndClearsOnAnEmptyRequest) {
  const HullRequest r = hidden_from_post(32, 20, 40, 7);
  hulls_->request(r);
  const HullSet* set = wait_for_set();
  ASSERT_NE(set, nullptr);
  EXPECT_EQ(set->sequence, 7u);
  EXPECT_TRUE(set->has_hidden);
  EXPECT_FALSE(set->has_visible);
  const Vec3 p(r.hidden_from_m[0], r.hidden_from_m[1], r.hidden_from_m[2]);
  Result<PointHull> direct = point_hull(field_->level(0), p, "p");
  ASSERT_TRUE(direct.ok());
  EXPECT_EQ(set->hidden.height_m, direct->height_m);
  EXPECT_EQ(set->hidden.nx, direct->nx);
  EXPECT_GT(hulls_->stats().last_build_ms, 0.0);

  HullRequest none;
  none.sequence = 8;
  hulls_->request(none);
  set = wait_for_set();
  ASSERT_NE(set, nullptr);
  EXPECT_EQ(set->sequence, 8u);
  EXPECT_FALSE(set->has_hidden);
  EXPECT_FALSE(set->has_visible);
  EXPECT_EQ(hulls_->stats().built, 2u);
}

TEST_F(ConstraintHullsTest, ARefusedPointLeavesTheSetInForceAndSaysWhy) {
  hulls_->request(hidden_from_post(10, 10, -5, 1));  // 5 m under its post
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (hulls_->stats().failed == 0 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const HullStats s = hulls_->stats();
  EXPECT_EQ(s.failed, 1u);
  EXPECT_EQ(s.built, 0u);
  EXPECT_NE(s.last_error.find("below the terrain"), std::string::npos) << s.last_error;
  EXPECT_EQ(hulls_->take(), nullptr);
}

TEST_F(ConstraintHullsTest, TheNewestRequestWinsAndAHeldSetIsNeverRewritten) {
  hulls_->request(hidden_from_post(5, 5, 30, 1));
  const HullSet* held = wait_for_set();
  ASSERT_NE(held, nullptr);
  const std::vector<float> before = held->hidden.height_m;
  // two more sets from elsewhere, built while the loop holds the first
  for (std::uint64_t seq : {2u, 3u}) {
    hulls_->request(hidden_from_post(50 + static_cast<int>(seq), 40, 80, seq));
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (hulls_->stats().built < seq && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  EXPECT_EQ(hulls_->stats().built, 3u);
  EXPECT_EQ(held->sequence, 1u);
  EXPECT_EQ(held->hidden.height_m, before);
  const HullSet* newest = hulls_->take();
  ASSERT_NE(newest, nullptr);
  EXPECT_EQ(newest->sequence, 3u);
  EXPECT_NE(newest->hidden.height_m, before);
  EXPECT_EQ(hulls_->take(), nullptr);
}

TEST(ConstraintHullsBudget, ReservesThreeSetsAndStatesWhatABuildAdds) {
  fields::VolumeGeometry g;
  g.nx = 370;
  g.ny = 466;
  EXPECT_EQ(ConstraintHulls::reserved_bytes(g), 6u * 370 * 466 * 4);
  // heightfield and hull, horizon 931^2, and the terrain padded by the radius
  // on every side (a height and a ground level, 8 bytes, a post)
  EXPECT_EQ(ConstraintHulls::build_bytes(g),
            (2u * 370 * 466 + 931u * 931) * 4 + fields::padded_terrain_bytes(370, 466, 465));
  EXPECT_GE(ConstraintHulls::build_bytes(g), (2u * 370 * 466 + 931u * 931) * 4 + 1300u * 1396 * 8);
}

}  // namespace
}  // namespace visvol::rt
