#include "rt/rope/l1_track.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace visvol::rt {
namespace {

double nearest_to(const FlownTrack& t, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const FlownPoint& q : t.points) best = std::min(best, (q.p_m - p).head<2>().norm());
  return best;
}

// A right-angle corner between two legs of 1000 m, north then east.
std::vector<Vec3> corner_path() { return {Vec3(0, 0, 100), Vec3(0, 1000, 100), Vec3(1000, 1000, 100)}; }

TEST(L1Track, AStraightPathIsFlownOnItsLineToItsEnd) {
  const std::vector<Vec3> path = {Vec3(0, 0, 100), Vec3(3000, 0, 160), Vec3(6000, 0, 100)};
  const FlownTrack t = fly_l1(path, L1Flight{});
  ASSERT_TRUE(t.reached_end);
  double off = 0;
  for (const FlownPoint& p : t.points) off = std::max(off, std::abs(p.p_m.y()));
  EXPECT_LT(off, 1e-6);
  // heights follow the leg flown; the last point within the switch distance of the end
  EXPECT_NEAR(t.points[t.points.size() / 2].p_m.z(), 160.0, 2.0);
  EXPECT_LE((t.points.back().p_m - path.back()).head<2>().norm(), 100.0 + 0.5);
}

TEST(L1Track, ACornerIsCutDeeperThanTheArcAtTheTurnRadius) {
  // Measured against an independent simulation (pure Python, written apart
  // from this code at stop 41): 45.5 m from the corner at its closest at
  // 20 m/s switching 100 m out, 57.2 m at 25 m/s switching 125 m out. The
  // arc at an 80 m radius passes 80 (sqrt 2 - 1) = 33.1 m from it.
  L1Flight f;
  const FlownTrack calm = fly_l1(corner_path(), f);
  ASSERT_TRUE(calm.reached_end);
  EXPECT_NEAR(nearest_to(calm, Vec3(0, 1000, 0)), 45.5, 1.0);
  f.ground_speed_m_per_s = 25;
  f.switch_distance_m = 125;
  const FlownTrack fast = fly_l1(corner_path(), f);
  EXPECT_NEAR(nearest_to(fast, Vec3(0, 1000, 0)), 57.2, 1.0);
  // after the switch, never past the chord between the switch points (125 m
  // along each leg: y - x = 875)
  for (const FlownPoint& p : fast.points) {
    if (p.leg == 1 && p.p_m.x() <= 125.0) {
      EXPECT_GE(p.p_m.y() - p.p_m.x(), 875.0 - 1e-6) << p.p_m.transpose();
    }
  }
}

TEST(L1Track, ItSettlesOnTheNextLegAfterTheCorner) {
  const FlownTrack t = fly_l1(corner_path(), L1Flight{});
  // overshoots the second leg's line by a few metres, then holds it
  double overshoot = 0;
  for (const FlownPoint& p : t.points) overshoot = std::max(overshoot, p.p_m.y() - 1000.0);
  EXPECT_GT(overshoot, 1.0);
  EXPECT_LT(overshoot, 10.0);
  for (const FlownPoint& p : t.points) {
    if (p.p_m.x() > 600) {
      EXPECT_NEAR(p.p_m.y(), 1000.0, 0.5) << p.p_m.x();
    }
  }
}

TEST(L1Track, AMirroredPathIsFlownMirrored) {
  std::vector<Vec3> path = {Vec3(0, 0, 80), Vec3(40, 300, 90), Vec3(-200, 420, 70), Vec3(-150, 500, 60),
                            Vec3(300, 900, 100)};
  std::vector<Vec3> mirrored = path;
  for (Vec3& p : mirrored) p.x() = -p.x();
  const FlownTrack a = fly_l1(path, L1Flight{}), b = fly_l1(mirrored, L1Flight{});
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_NEAR(a.points[i].p_m.x(), -b.points[i].p_m.x(), 1e-6);
    EXPECT_NEAR(a.points[i].p_m.y(), b.points[i].p_m.y(), 1e-6);
    EXPECT_EQ(a.points[i].leg, b.points[i].leg);
  }
}

TEST(L1Track, LegsShorterThanTheSwitchDistanceAreCutTogether) {
  // a zigzag of 60 m legs: each waypoint is taken before the last is
  // reached, and the track runs down the middle
  std::vector<Vec3> path;
  for (int k = 0; k <= 20; ++k) path.emplace_back(k % 2 ? 30.0 : 0.0, 60.0 * k, 100.0);
  path.emplace_back(15.0, 60.0 * 20 + 1000.0, 100.0);
  const FlownTrack t = fly_l1(path, L1Flight{});
  ASSERT_TRUE(t.reached_end);
  EXPECT_EQ(t.points.back().leg, static_cast<int>(path.size()) - 2);
  // it never flies out to the zigzag's outer corners
  double widest = 0;
  for (const FlownPoint& p : t.points) {
    if (p.p_m.y() > 200 && p.p_m.y() < 1000) widest = std::max(widest, std::abs(p.p_m.x() - 15.0));
  }
  EXPECT_LT(widest, 15.0);
}

TEST(L1Track, NothingIsFlownWithoutTwoWaypointsApart) {
  EXPECT_TRUE(fly_l1({Vec3(0, 0, 100)}, L1Flight{}).points.empty());
  EXPECT_TRUE(fly_l1({Vec3(0, 0, 100), Vec3(0, 0, 200)}, L1Flight{}).points.empty());
  L1Flight stopped;
  stopped.ground_speed_m_per_s = 0;
  EXPECT_TRUE(fly_l1(corner_path(), stopped).points.empty());
}

TEST(L1Track, AnAircraftThatCannotTurnStopsShortOfTheEndInBoundedTime) {
  // a 1 degree bank cannot make the corner: it flies on and circles back
  // far out, and stops at three times the path's flight time and 2 min more
  L1Flight stiff;
  stiff.max_roll_deg = 1;
  const FlownTrack t = fly_l1(corner_path(), stiff);
  EXPECT_FALSE(t.reached_end);
  const double steps = (3.0 * 2000.0 / 20.0 + 120.0) / stiff.step_s;
  EXPECT_LE(t.points.size(), static_cast<std::size_t>(steps) + 2);
  for (const FlownPoint& p : t.points) EXPECT_TRUE(p.p_m.allFinite());
}

TEST(L1Track, PointsAreKeptAsFarApartAsAsked) {
  L1Flight sparse;
  sparse.record_every_m = 5;
  const FlownTrack every = fly_l1(corner_path(), L1Flight{}), t = fly_l1(corner_path(), sparse);
  ASSERT_TRUE(t.reached_end);
  EXPECT_LT(t.points.size(), every.points.size() / 10);
  for (std::size_t i = 1; i + 1 < t.points.size(); ++i) {
    EXPECT_GE((t.points[i].p_m - t.points[i - 1].p_m).head<2>().norm(), 5.0 - 1e-9);
  }
  // the same flight: it stops where the dense one does
  EXPECT_LT((t.points.back().p_m - every.points.back().p_m).norm(), 1e-9);
}

TEST(L1Track, AClimbOnTheStartsSpotIsFlownFromTheFirstWaypointOffIt) {
  std::vector<Vec3> path = corner_path();
  path.insert(path.begin() + 1, Vec3(0, 0, 150));  // up 50 m before leaving
  const FlownTrack t = fly_l1(path, L1Flight{});
  ASSERT_TRUE(t.reached_end);
  EXPECT_NEAR(nearest_to(t, Vec3(0, 1000, 0)), 45.5, 1.0);  // the corner flown as without the climb
}

TEST(L1Track, ItAlwaysStopsAndStaysFinite) {
  // a path that doubles back on itself within the switch distance
  const std::vector<Vec3> path = {Vec3(0, 0, 100), Vec3(0, 50, 100), Vec3(0, 0, 100), Vec3(0, 50, 100)};
  const FlownTrack t = fly_l1(path, L1Flight{});
  ASSERT_FALSE(t.points.empty());
  for (const FlownPoint& p : t.points) EXPECT_TRUE(p.p_m.allFinite());
}

}  // namespace
}  // namespace visvol::rt
