// The hull builder beside the loop: what it builds is point_hull's for every
// observer of a set (several of each kind), the newest request wins, a
// refused request leaves the set in force, a set the loop holds is never
// rewritten under it, and no set holds more than was reserved.
#include "rt/exec/constraint_hulls.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "../../fields/terrains.hpp"
#include "fields/hull_kernel.hpp"
#include "rt/rope/point_hull_maker.hpp"
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
    auto h = ConstraintHulls::create(field_->level(0), ConstraintHulls::kMaxObservers);
    ASSERT_TRUE(h.ok()) << h.status().message();
    hulls_ = std::move(*h);
    hulls_->start();
  }

  // A post's position, `up_m` above its height.
  Vec3 post(int i, int j, double up_m) const {
    const storage::ResidentLevel& l = field_->level(0);
    const fields::VolumeGeometry& g = l.geometry();
    return {g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, l.post(i, j) + up_m};
  }
  HullRequest hidden_from_post(int i, int j, double up_m, std::uint64_t sequence) const {
    HullRequest r;
    r.sequence = sequence;
    r.eye_height_m = 0;
    EXPECT_TRUE(r.add_hidden_from(post(i, j, up_m)));
    return r;
  }
  // What point_hull builds for an observer standing at p (its eye as the builder puts it).
  PointHull direct(const Vec3& p, double eye_height_m) const {
    Result<PointHull> h = point_hull(field_->level(0), p + Vec3(0, 0, eye_height_m), "p");
    EXPECT_TRUE(h.ok()) << h.status().message();
    return h.ok() ? *h : PointHull{};
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
  EXPECT_EQ(set->sequence(), 7u);
  ASSERT_EQ(set->hidden_count(), 1);
  EXPECT_EQ(set->visible_count(), 0);
  const PointHull expected = direct(HullRequest::point(r.hidden_from_m[0]), 0.0);
  ASSERT_NE(set->hidden, nullptr);
  EXPECT_EQ(set->visible, nullptr);
  EXPECT_EQ(set->hidden->height_m, expected.height_m);
  EXPECT_EQ(set->hidden->nx, expected.nx);
  EXPECT_GT(hulls_->stats().last_build_ms, 0.0);

  HullRequest none;
  none.sequence = 8;
  hulls_->request(none);
  set = wait_for_set();
  ASSERT_NE(set, nullptr);
  EXPECT_EQ(set->sequence(), 8u);
  EXPECT_EQ(set->hidden_count(), 0);
  EXPECT_EQ(set->visible_count(), 0);
  EXPECT_EQ(set->hidden, nullptr);
  EXPECT_EQ(hulls_->stats().built, 2u);
}

// Observers of a kind are folded into one hull: post by post the lowest of
// the hidden-from hulls (hidden from all of them) and the highest of the
// visible-to hulls (visible to all), each observer's eye lifted by the eye
// height. A request holds kMaxObserversPerKind of a kind and no more.
TEST_F(ConstraintHullsTest, EveryObserverIsFoldedIntoItsKindsHull) {
  HullRequest r;
  r.sequence = 3;
  r.eye_height_m = 2.0;
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(r.add_hidden_from(post(4 + 11 * k, 10 + 6 * k, 30 + k)));
  for (int k = 0; k < 4; ++k) ASSERT_TRUE(r.add_visible_to(post(60 - 9 * k, 50 - 5 * k, 5 + k)));
  hulls_->request(r);
  const HullSet* set = wait_for_set(60.0);
  ASSERT_NE(set, nullptr);
  ASSERT_EQ(set->hidden_count(), 5);
  ASSERT_EQ(set->visible_count(), 4);
  ASSERT_NE(set->hidden, nullptr);
  ASSERT_NE(set->visible, nullptr);
  std::vector<float> lowest = direct(HullRequest::point(r.hidden_from_m[0]), 2.0).height_m;
  std::vector<float> highest = direct(HullRequest::point(r.visible_to_m[0]), 2.0).height_m;
  bool folded_differs = false;  // the fold is not just the first hull
  for (int k = 1; k < 5; ++k) {
    const std::vector<float> h = direct(HullRequest::point(r.hidden_from_m[k]), 2.0).height_m;
    for (std::size_t i = 0; i < h.size(); ++i) {
      folded_differs |= h[i] < lowest[i];
      lowest[i] = std::min(lowest[i], h[i]);
    }
  }
  for (int k = 1; k < 4; ++k) {
    const std::vector<float> h = direct(HullRequest::point(r.visible_to_m[k]), 2.0).height_m;
    for (std::size_t i = 0; i < h.size(); ++i) highest[i] = std::max(highest[i], h[i]);
  }
  EXPECT_TRUE(folded_differs);
  EXPECT_EQ(set->hidden->height_m, lowest);
  EXPECT_EQ(set->visible->height_m, highest);
  EXPECT_EQ(set->request.eye_height_m, 2.0);
  EXPECT_EQ(set->request.visible_to_m[3][0], r.visible_to_m[3][0]);

  HullRequest full;
  for (int k = 0; k < kMaxObserversPerKind; ++k) {
    ASSERT_TRUE(full.add_hidden_from(post(1, 1, 1)));
    ASSERT_TRUE(full.add_visible_to(post(1, 1, 1)));
  }
  EXPECT_FALSE(full.add_hidden_from(post(1, 1, 1))) << "one more than a kind holds";
  EXPECT_FALSE(full.add_visible_to(post(1, 1, 1)));
  EXPECT_EQ(full.observers(), ConstraintHulls::kMaxObservers);
}

// A build of many observers gives way to a newer request between observers:
// the newest set comes into force and the one given up is not a refusal.
TEST_F(ConstraintHullsTest, ANewerRequestSupersedesABuildInProgress) {
  HullRequest many;
  many.sequence = 1;
  for (int k = 0; k < 60; ++k) ASSERT_TRUE(many.add_hidden_from(post(2 + k, 10 + (k % 40), 30)));
  hulls_->request(many);
  hulls_->request(hidden_from_post(32, 20, 40, 2));
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  const HullSet* newest = nullptr;
  while (std::chrono::steady_clock::now() < end) {
    if (const HullSet* s = hulls_->take()) newest = s;
    if (newest != nullptr && newest->sequence() == 2u) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_NE(newest, nullptr);
  EXPECT_EQ(newest->sequence(), 2u);
  EXPECT_EQ(newest->hidden_count(), 1);
  EXPECT_EQ(hulls_->stats().failed, 0u);
  EXPECT_EQ(hulls_->refused_sequence(), 0u);
  // and a single build told to give up says so
  HullSet set = hulls_->reserve_set();
  hulls_->request(hidden_from_post(5, 5, 30, 3));  // fresh, not yet taken: supersedes what follows
  hulls_->stop();
  const Status s = hulls_->build(many, set);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), Errc::state);
  EXPECT_NE(s.message().find("superseded"), std::string::npos) << s.message();
}

TEST_F(ConstraintHullsTest, ARefusedPointLeavesTheSetInForceAndSaysWhy) {
  HullRequest outside = hidden_from_post(10, 10, 5, 1);
  outside.hidden_from_m[0][0] -= 1e6;  // far west of the pack
  hulls_->request(outside);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (hulls_->stats().failed == 0 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const HullStats s = hulls_->stats();
  EXPECT_EQ(s.failed, 1u);
  EXPECT_EQ(s.built, 0u);
  EXPECT_EQ(hulls_->refused_sequence(), 1u);
  EXPECT_NE(s.last_error.find("outside the pack"), std::string::npos) << s.last_error;
  EXPECT_EQ(hulls_->take(), nullptr);
}

// A builder that takes two observers refuses three, naming both counts; its
// sets hold the two folded hulls whatever the number.
TEST_F(ConstraintHullsTest, MoreObserversThanReservedAreRefusedWithAReason) {
  auto small = ConstraintHulls::create(field_->level(0), 2);
  ASSERT_TRUE(small.ok());
  EXPECT_EQ((*small)->max_observers(), 2);
  HullSet set = (*small)->reserve_set();
  EXPECT_EQ(set.hulls.size(), 2u);
  HullRequest r = hidden_from_post(10, 10, 20, 1);
  ASSERT_TRUE(r.add_visible_to(post(20, 20, 20)));
  EXPECT_TRUE((*small)->build(r, set).ok());
  EXPECT_EQ(set.hidden_count(), 1);
  EXPECT_EQ(set.visible_count(), 1);
  ASSERT_TRUE(r.add_visible_to(post(30, 30, 20)));
  const Status s = (*small)->build(r, set);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("1 hidden-from and 2 visible-to points: this console takes 2"), std::string::npos)
      << s.message();
  EXPECT_FALSE(ConstraintHulls::create(field_->level(0), ConstraintHulls::kMaxObservers + 1).ok());
  EXPECT_FALSE(ConstraintHulls::create(field_->level(0), -1).ok());
}

TEST_F(ConstraintHullsTest, TheNewestRequestWinsAndAHeldSetIsNeverRewritten) {
  hulls_->request(hidden_from_post(5, 5, 30, 1));
  const HullSet* held = wait_for_set();
  ASSERT_NE(held, nullptr);
  const std::vector<float> before = held->hidden->height_m;
  // two more sets from elsewhere, built while the loop holds the first
  for (std::uint64_t seq : {2u, 3u}) {
    hulls_->request(hidden_from_post(50 + static_cast<int>(seq), 40, 80, seq));
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (hulls_->stats().built < seq && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  EXPECT_EQ(hulls_->stats().built, 3u);
  EXPECT_EQ(held->sequence(), 1u);
  EXPECT_EQ(held->hidden->height_m, before);
  const HullSet* newest = hulls_->take();
  ASSERT_NE(newest, nullptr);
  EXPECT_EQ(newest->sequence(), 3u);
  EXPECT_NE(newest->hidden->height_m, before);
  EXPECT_EQ(hulls_->take(), nullptr);
}

TEST(ConstraintHullsBudget, ReservesThreeSetsOfTwoFoldedHullsAndStatesWhatABuildAdds) {
  fields::VolumeGeometry g;
  g.nx = 370;
  g.ny = 466;
  // observers cost no memory: three sets of two hulls for any number, none for none
  EXPECT_EQ(ConstraintHulls::reserved_bytes(g, ConstraintHulls::kMaxObservers), 3u * 2 * 370 * 466 * 4);
  EXPECT_EQ(ConstraintHulls::reserved_bytes(g, 1), 3u * 2 * 370 * 466 * 4);
  EXPECT_EQ(ConstraintHulls::reserved_bytes(g, 0), 0u);
  // all observers where the sets fit, none where they do not
  EXPECT_EQ(ConstraintHulls::observers_within(g, ConstraintHulls::reserved_bytes(g, 1)),
            ConstraintHulls::kMaxObservers);
  EXPECT_EQ(ConstraintHulls::observers_within(g, ConstraintHulls::reserved_bytes(g, 1) - 1), 0);
  EXPECT_EQ(ConstraintHulls::observers_within(g, std::uint64_t{1} << 40), ConstraintHulls::kMaxObservers);
  // heightfield and hull, horizon 931^2, and the terrain padded by a few posts
  // on every side (a height and a ground level, 8 bytes, a post): grid-only
  // horizons need no padding of the radius
  EXPECT_EQ(ConstraintHulls::build_bytes(g),
            (2u * 370 * 466 + 931u * 931) * 4 + fields::padded_terrain_bytes(370, 466, 2));
  EXPECT_GE(ConstraintHulls::build_bytes(g), (2u * 370 * 466 + 931u * 931) * 4 + 374u * 470 * 8);
  EXPECT_LT(ConstraintHulls::build_bytes(g), (2u * 370 * 466 + 931u * 931) * 4 + 450u * 550 * 8);
}

}  // namespace
}  // namespace visvol::rt
