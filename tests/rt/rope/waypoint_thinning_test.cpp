// Waypoint thinning: which vertices a path keeps, and how near the legs that
// replace them pass the ones it drops.
#include "rt/rope/waypoint_thinning.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../fields/terrains.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/track_ground.hpp"
#include "rt/rope/vehicle.hpp"

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

// Vertices marked to keep stay, and the spans between them thin on their own.
TEST(WaypointThinning, MarkedVerticesStay) {
  std::vector<Vec3> line;
  for (int i = 0; i <= 30; ++i) line.emplace_back(3.0 * i, 0.0, 100.0);
  std::vector<bool> keep(line.size(), false);
  keep[7] = keep[20] = true;
  EXPECT_EQ(thinned_indices(line, {}, &keep), (std::vector<int>{0, 7, 20, 30}));
}

// A turn near the least radius keeps its vertices (its legs must stay near
// equal for the fillets to fit); the same arc for a vehicle of a third of that
// radius or less thins, and keeps room for that vehicle's turns.
TEST(WaypointThinning, TurnsNearTheLeastRadiusKeepTheirVertices) {
  std::vector<Vec3> arc;  // 200 m radius, a vertex every 3 m, straight legs in and out
  for (int i = -20; i < 0; ++i) arc.emplace_back(3.0 * i, -200.0, 80.0);
  for (int i = 0; i <= 100; ++i) {
    const double a = 3.0 * i / 200.0;
    arc.emplace_back(200.0 * std::sin(a), -200.0 * std::cos(a), 80.0);
  }
  const std::vector<bool> tight = turns_to_keep(arc, 200.0);
  const std::vector<Vec3> kept = thin_waypoints(arc, {}, &tight);
  EXPECT_GE(kept.size(), 100u);  // the arc's 101, less those where it meets the straight run
  for (double r : turn_radii_m(kept.data(), static_cast<int>(kept.size()))) EXPECT_GE(r, 195.0);
  const std::vector<bool> wide = turns_to_keep(arc, 50.0);
  const std::vector<Vec3> thinned = thin_waypoints(arc, {}, &wide);
  EXPECT_LT(thinned.size(), 20u);
  for (double r : turn_radii_m(thinned.data(), static_cast<int>(thinned.size()))) EXPECT_GE(r, 50.0);
  EXPECT_TRUE(turns_to_keep(arc, 0.0) == std::vector<bool>(arc.size(), false));
}

// A contrived path (a zigzag of growing height: each split peels one vertex
// off a span) costs n^2 deviations: past the bound it is left as it is, the
// midpoints of its legs too (which a shorter one loses).
TEST(WaypointThinning, AContrivedPathIsLeftAsItIs) {
  auto zigzag = [](int corners) {
    std::vector<Vec3> p;
    for (int i = 0; i < corners; ++i) {
      const Vec3 corner(4.0 * i, 0.0, 100.0 + (i % 2) * (1.0 + i));
      if (i > 0) p.push_back(0.5 * (p.back() + corner));  // on the leg: nothing needs it
      p.push_back(corner);
    }
    return p;
  };
  const std::vector<Vec3> short_one = zigzag(20);
  EXPECT_EQ(thinned_indices(short_one, {}).size(), 20u);
  const std::vector<Vec3> long_one = zigzag(3000);
  EXPECT_EQ(thinned_indices(long_one, {}).size(), long_one.size());
  std::vector<Vec3> line;  // a long straight run is cheap: one span
  for (int i = 0; i < 100000; ++i) line.emplace_back(3.0 * i, 0.0, 100.0);
  EXPECT_EQ(thinned_indices(line, {}).size(), 2u);
}

// Thinning joins no vertices into a leg no longer than the acceptance radius
// whose lower end would be held under the clearance over the ground from the
// radius before it (PX4 steps to that height there): a straight descent past
// a ridge keeps the vertices that hold it, and every leg it keeps holds.
TEST(WaypointThinning, AShortLegHeldUnderTheClearanceIsNotJoined) {
  fields::Heightfield t = fields::testing::blank(60, 5, 10.0, 0.0f);
  for (int j = 0; j < 5; ++j) t.at(17, j) = 55.0f;  // 150 m along
  std::vector<Vec3> path = {{t.x_of(2), t.y_of(2), 100.0}};
  for (int i = 24; i <= 32; ++i) path.emplace_back(t.x_of(i), t.y_of(2), 100.0 - 2.5 * (i - 24));  // 14 deg down
  path.emplace_back(t.x_of(57), t.y_of(2), 80.0);
  VehicleEnvelope e = *vehicle_preset("fixed-wing");  // 30 m, 100 m early in calm air
  e.max_wind_m_per_s = 0;
  ASSERT_EQ(thin_waypoints(path, {}).size(), 4u);  // the shape alone: start, the leg's two ends, the end
  const LegTest held = held_legs(path, e, t);
  EXPECT_FALSE(held(1, 9));  // the leg down: 80 m, held 25 m over the ridge
  for (int k = 0; k + 1 < static_cast<int>(path.size()); ++k) ASSERT_TRUE(held(k, k + 1)) << k;
  const std::vector<int> kept = thinned_indices(path, {}, nullptr, &held);
  expect_within_tolerance(path, kept, {});
  EXPECT_GT(kept.size(), 4u);
  const TrackGround g(t, path.data(), static_cast<int>(path.size()));
  for (std::size_t q = 1; q < kept.size(); ++q) {
    const int a = kept[q - 1], b = kept[q];
    EXPECT_TRUE(held(a, b)) << a << "-" << b;
    const double run = std::hypot(path[static_cast<std::size_t>(b)].x() - path[static_cast<std::size_t>(a)].x(), 0.0);
    if (run <= e.acceptance_radius_m) {
      EXPECT_GE(g.held_clearance_m(a, b, path[static_cast<std::size_t>(a)].z(), path[static_cast<std::size_t>(b)].z(),
                                   e.acceptance_radius_m),
                e.clearance_m + kThinnedHeldMarginM);
    }
  }
  // a multirotor reaches each waypoint: nothing held
  EXPECT_TRUE(held_legs(path, *vehicle_preset("multirotor"), t)(1, 9));
  // In the preset's 5 m/s of wind PX4 switches 125 m out: a 110 m leg down
  // past the ridge, ramped in calm air, is held at its lower end over it.
  const std::vector<Vec3> longer = {{t.x_of(2), t.y_of(2), 100.0},
                                    {t.x_of(24), t.y_of(2), 100.0},
                                    {t.x_of(35), t.y_of(2), 80.0},
                                    {t.x_of(57), t.y_of(2), 80.0}};
  EXPECT_TRUE(held_legs(longer, e, t)(1, 2));
  EXPECT_FALSE(held_legs(longer, *vehicle_preset("fixed-wing"), t)(1, 2));
}

// The console's final path and the planner's answer are thinned only where
// the thinned path, judged again, meets as much: a leg may cross what its
// vertices went over (here a 15 cm post under a path held exactly at its 30 m
// clearance, within the 20 cm vertical tolerance).
TEST(ThinnedAsGood, KeptOnlyWhereItMeetsAsMuch) {
  fields::Heightfield t = fields::testing::blank(20, 5, 10.0, 0.0f);
  PathCheckSpec spec;
  spec.envelope = *vehicle_preset("multirotor");
  spec.envelope.clearance_m = 30;
  spec.envelope.max_agl_m = 200;
  auto along_row = [&]() {
    std::vector<Vec3> p;
    for (int i = 2; i <= 17; ++i) p.emplace_back(t.x_of(i), t.y_of(2), 30.0 + t.at(i, 2));
    return p;
  };
  {
    const auto checker = PathChecker::create(t, nullptr, spec);
    ASSERT_TRUE(checker.ok()) << checker.status().message();
    const std::vector<Vec3> level = along_row();
    const std::optional<ThinnedPath> thinned = thinned_as_good(level, checker->check(level), *checker, Objective::hide);
    ASSERT_TRUE(thinned.has_value());
    EXPECT_EQ(thinned->path.size(), 2u);
    EXPECT_TRUE(thinned->check.all_met);
  }
  t.at(10, 2) = 0.15f;
  const auto checker = PathChecker::create(t, nullptr, spec);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const std::vector<Vec3> over_post = along_row();
  const PathCheck fitted = checker->check(over_post);
  ASSERT_TRUE(fitted.all_met);
  // thinned, its one leg passes 29.85 m over the post
  ASSERT_FALSE(checker->check(thin_waypoints(over_post, {})).all_met);
  EXPECT_FALSE(thinned_as_good(over_post, fitted, *checker, Objective::hide).has_value());
}

}  // namespace
}  // namespace visvol::rt
