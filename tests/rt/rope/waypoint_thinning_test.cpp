// Waypoint thinning: which vertices a path keeps, and how near the legs that
// replace them pass the ones it drops.
#include "rt/rope/waypoint_thinning.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace visvol::rt {
namespace {

// Every vertex between two kept ones lies within the tolerance of the leg
// joining them; the kept ones are in order and include both ends.
void expect_within_tolerance(const std::vector<Vec3>& path, const std::vector<int>& kept,
                             const ThinningTolerance& tol) {
  ASSERT_GE(kept.size(), std::min<std::size_t>(path.size(), 2));
  EXPECT_EQ(kept.front(), 0);
  EXPECT_EQ(kept.back(), static_cast<int>(path.size()) - 1);
  for (std::size_t q = 1; q < kept.size(); ++q) {
    ASSERT_LT(kept[q - 1], kept[q]);
    const Vec3& a = path[static_cast<std::size_t>(kept[q - 1])];
    const Vec3& b = path[static_cast<std::size_t>(kept[q])];
    for (int k = kept[q - 1] + 1; k < kept[q]; ++k) {
      EXPECT_LE(thinning_deviation(a, b, path[static_cast<std::size_t>(k)], tol), 1.0) << "vertex " << k;
    }
  }
}

// The envelope fit's split points along a straight climb: one leg.
TEST(WaypointThinning, ARunOfSplitPointsOnOneLineIsOneLeg) {
  std::vector<Vec3> path;
  for (int i = 0; i <= 200; ++i) path.emplace_back(3.0 * i, 1.5 * i, 100.0 + 0.8 * i);
  const std::vector<Vec3> thinned = thin_waypoints(path, {});
  ASSERT_EQ(thinned.size(), 2u);
  EXPECT_EQ(thinned.front(), path.front());
  EXPECT_EQ(thinned.back(), path.back());
}

// Random wanders: whatever goes, the legs pass within the tolerance of it.
TEST(WaypointThinning, EveryDroppedVertexLiesWithinTheToleranceOfItsLeg) {
  std::mt19937 rng(38);
  std::normal_distribution<double> step(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const ThinningTolerance tol{0.2 + 0.1 * (trial % 7), 0.05 + 0.05 * (trial % 5)};
    std::vector<Vec3> path{Vec3(0, 0, 100)};
    const int n = 2 + trial % 150;
    for (int i = 1; i < n; ++i) {
      // mostly straight ahead, with small wobbles and now and then a bend
      const double bend = trial % 3 == 0 ? 3.0 : 0.3;
      path.push_back(path.back() + Vec3(4.0, bend * step(rng), 0.3 * step(rng)));
    }
    const std::vector<int> kept = thinned_indices(path, tol);
    expect_within_tolerance(path, kept, tol);
    EXPECT_EQ(thin_waypoints(path, tol).size(), kept.size());
  }
}

// A zigzag wider than the tolerance keeps every vertex, across or up and down.
TEST(WaypointThinning, AZigzagWiderThanTheToleranceKeepsEveryVertex) {
  const ThinningTolerance tol{0.5, 0.2};
  std::vector<Vec3> across, vertical;
  for (int i = 0; i < 20; ++i) {
    across.emplace_back(10.0 * i, i % 2 == 0 ? 0.0 : 1.2, 50.0);
    vertical.emplace_back(10.0 * i, 0.0, i % 2 == 0 ? 50.0 : 50.5);
  }
  EXPECT_EQ(thinned_indices(across, tol).size(), across.size());
  EXPECT_EQ(thinned_indices(vertical, tol).size(), vertical.size());
  // within it, they go
  for (Vec3& p : across) p.y() *= 0.3;
  for (Vec3& p : vertical) p.z() = 50.0 + (p.z() - 50.0) * 0.3;
  EXPECT_EQ(thinned_indices(across, tol).size(), 2u);
  EXPECT_EQ(thinned_indices(vertical, tol).size(), 2u);
}

// A multirotor's climb on the spot: the points on it go, one beside it stays,
// and so does one above its top (it would be a climb the legs do not make).
TEST(WaypointThinning, AClimbOnTheSpotKeepsOnlyWhatLeavesIt) {
  const ThinningTolerance tol{0.5, 0.2};
  const std::vector<Vec3> on{{0, 0, 50}, {0, 0, 60}, {0, 0, 70}, {0, 0, 80}};
  EXPECT_EQ(thinned_indices(on, tol), (std::vector<int>{0, 3}));
  // (the steep leg to the point beside is judged where each point lies seen
  // from above: 10 m under the one at 60 m, which stays too)
  const std::vector<Vec3> beside{{0, 0, 50}, {0, 0, 60}, {1, 0, 70}, {0, 0, 80}};
  EXPECT_EQ(thinned_indices(beside, tol), (std::vector<int>{0, 1, 2, 3}));
  const std::vector<Vec3> over{{0, 0, 50}, {0, 0, 90}, {0, 0, 80}};
  EXPECT_EQ(thinned_indices(over, tol), (std::vector<int>{0, 1, 2}));
}

// A vertex that is not a number is never within a tolerance: it stays (for
// the checker to refuse), and so do short paths and both ends.
TEST(WaypointThinning, NothingUnknownIsDropped) {
  const ThinningTolerance tol{0.5, 0.2};
  const std::vector<Vec3> nan{{0, 0, 50}, {10, 0, std::nan("")}, {20, 0, 50}};
  EXPECT_EQ(thinned_indices(nan, tol).size(), 3u);
  EXPECT_EQ(thinned_indices({{0, 0, 0}, {1, 0, 0}}, tol), (std::vector<int>{0, 1}));
  EXPECT_EQ(thinned_indices({{0, 0, 0}}, tol), (std::vector<int>{0}));
  EXPECT_TRUE(thinned_indices({}, tol).empty());
}

}  // namespace
}  // namespace visvol::rt
