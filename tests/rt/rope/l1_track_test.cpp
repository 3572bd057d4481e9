#include "rt/rope/l1_track.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "base/angles.hpp"

namespace visvol::rt {
namespace {

double nearest_to(const FlownTrack& t, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const FlownPoint& q : t.points) best = std::min(best, (q.p_m - p).head<2>().norm());
  return best;
}

// A right-angle corner between two legs of 1000 m, north then east.
std::vector<Vec3> corner_path() { return {Vec3(0, 0, 100), Vec3(0, 1000, 100), Vec3(1000, 1000, 100)}; }

TEST(L1Track, SinEtaIsTheTrigonometricFormulasEverywhere) {
  // sin(clamp(asin(s1) + atan2(c, d), -90, 90 degrees)), as PX4 writes it,
  // over cross-track sines within +-0.7071 and headings half a degree apart,
  // the clamp's edges and a velocity of 0 (either zero's sign) included
  auto formula = [](double s1, double c, double d) {
    return std::sin(std::clamp(std::asin(s1) + std::atan2(c, d), -0.5 * kPi, 0.5 * kPi));
  };
  double worst = 0;
  for (int i = -20; i <= 20; ++i) {
    const double s1 = 0.7071 * i / 20.0;
    for (int k = 0; k < 720; ++k) {
      const double heading = 2.0 * kPi * k / 720.0, v = 17.5;
      const double c = v * std::sin(heading), d = v * std::cos(heading);
      worst = std::max(worst, std::abs(l1_sin_eta(s1, c, d) - formula(s1, c, d)));
    }
    EXPECT_DOUBLE_EQ(l1_sin_eta(s1, 0.0, 0.0), formula(s1, 0.0, 0.0));
    EXPECT_DOUBLE_EQ(l1_sin_eta(s1, 0.0, -3.0), formula(s1, 0.0, -3.0));
    EXPECT_DOUBLE_EQ(l1_sin_eta(s1, -0.0, -3.0), formula(s1, -0.0, -3.0));
    EXPECT_DOUBLE_EQ(l1_sin_eta(s1, 0.0, -0.0), formula(s1, 0.0, -0.0));
    EXPECT_DOUBLE_EQ(l1_sin_eta(s1, -0.0, -0.0), formula(s1, -0.0, -0.0));
  }
  EXPECT_LT(worst, 1e-12);
}

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

// The height flown at x along a path flown due east (the first point at or past x).
double height_at(const FlownTrack& t, double x) {
  for (const FlownPoint& q : t.points) {
    if (q.p_m.x() >= x) return q.p_m.z();
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// PX4 1.13's first-order hold: a long leg's setpoint reaches its end height
// H before the end (H = 100 m here), so a descent is flown that much early;
// a leg no longer than H steps to its end height when the aircraft takes its
// start, and is flown down at the sink rate. By hand: a 100 m descent over
// 1000 m ramps over 900 m.
TEST(L1Track, HeightsFollowPx4sFirstOrderHoldAtTheVehiclesRates) {
  L1Flight f;  // 20 m/s, switch distance 100 m
  f.altitude_hold_m = 100.0;
  f.max_climb_m_per_s = f.max_sink_m_per_s = 20.0 * std::tan(15.0 * kPi / 180.0);  // 5.36 m/s
  f.step_s = 0.001;                                                                // to the centimetre
  const std::vector<Vec3> ramp = {Vec3(0, 0, 200), Vec3(1000, 0, 100), Vec3(2000, 0, 100)};
  const FlownTrack r = fly_l1(ramp, f);
  ASSERT_TRUE(r.reached_end);
  EXPECT_NEAR(height_at(r, 450.0), 200.0 - 100.0 * 450.0 / 900.0, 0.1);  // the leg would be 155
  EXPECT_NEAR(height_at(r, 900.0), 100.0, 0.1);                          // the leg would be 110
  EXPECT_NEAR(height_at(r, 1500.0), 100.0, 1e-9);
  // a leg of 80 m: its 40 m descent begins where its start is taken, 100 m
  // before it, at 5.36 m/s (0.268 m a metre), and is done 149 m later
  const std::vector<Vec3> step = {Vec3(0, 0, 100), Vec3(1000, 0, 100), Vec3(1080, 0, 60), Vec3(3000, 0, 60)};
  const FlownTrack s = fly_l1(step, f);
  ASSERT_TRUE(s.reached_end);
  EXPECT_NEAR(height_at(s, 890.0), 100.0, 1e-9);
  EXPECT_NEAR(height_at(s, 1000.0), 100.0 - 0.268 * 100.0, 0.1);  // the leg would be 100
  EXPECT_NEAR(height_at(s, 1100.0), 60.0, 1e-9);
  // a climb within the climb rate is flown as early, never under the leg
  const std::vector<Vec3> climb = {Vec3(0, 0, 100), Vec3(1000, 0, 200), Vec3(2000, 0, 200)};
  const FlownTrack c = fly_l1(climb, f);
  for (const FlownPoint& q : c.points) EXPECT_GE(q.p_m.z(), std::min(200.0, 100.0 + 0.1 * q.p_m.x()) - 0.01);
  // without a hold, the leg's own heights (the default)
  EXPECT_NEAR(height_at(fly_l1(ramp, L1Flight{}), 900.0), 110.0, 0.1);
}

// The climb rate is the airframe's: with 5 m/s of wind behind it a
// fixed-wing flies 25 m/s over the ground and climbs 5.36 m/s, 0.214 m a
// metre, so a climb planned at its 15 deg (0.268 m a metre) falls behind:
// by hand, 1000 m of it begins at the leg's start (the hold's ramp asks more
// than the rate from there) and is 54 m short at the leg's end.
TEST(L1Track, ATailwindClimbsLessAMetreThanTheLegAsks) {
  L1Flight f;
  f.ground_speed_m_per_s = 25.0;
  f.altitude_hold_m = f.l1_distance_m();  // 119.4 m
  f.max_climb_m_per_s = f.max_sink_m_per_s = 20.0 * std::tan(15.0 * kPi / 180.0);
  f.step_s = 0.001;
  const double slope = std::tan(15.0 * kPi / 180.0);
  const std::vector<Vec3> climb = {Vec3(0, 0, 100), Vec3(1000, 0, 100 + 1000 * slope),
                                   Vec3(3000, 0, 100 + 1000 * slope)};
  const FlownTrack c = fly_l1(climb, f);
  ASSERT_TRUE(c.reached_end);
  EXPECT_NEAR(height_at(c, 500.0), 100.0 + 500.0 * 0.8 * slope, 0.1);
  EXPECT_NEAR(height_at(c, 1000.0), 100.0 + 1000.0 * 0.8 * slope, 0.1);  // 53.6 m under the waypoint
  EXPECT_NEAR(height_at(c, 1300.0), 100.0 + 1000.0 * slope, 1e-9);
}

// PX4 keeps the least distance to the waypoint since it took it, anew for
// each waypoint: the second of two climbs of 100 m over 1000 m ramps from
// its start height again (at 1500 m, 500 m from its end: 200 + 100 x 500 /
// 900), not from the first's least distance (which would ask for 300 m at
// once).
TEST(L1Track, EachLegsHoldStartsAgainFromItsOwnStart) {
  L1Flight f;
  f.altitude_hold_m = 100.0;
  f.max_climb_m_per_s = f.max_sink_m_per_s = 20.0 * std::tan(15.0 * kPi / 180.0);
  f.altitude_gate_m = 10.0;
  f.step_s = 0.001;
  const std::vector<Vec3> climbs = {Vec3(0, 0, 100), Vec3(1000, 0, 200), Vec3(2000, 0, 300), Vec3(3000, 0, 300)};
  const FlownTrack c = fly_l1(climbs, f);
  ASSERT_TRUE(c.reached_end);
  EXPECT_NEAR(height_at(c, 900.0), 200.0, 0.1);
  EXPECT_NEAR(height_at(c, 1500.0), 200.0 + 100.0 * 500.0 / 900.0, 0.1);
  EXPECT_NEAR(height_at(c, 1900.0), 300.0, 0.1);
}

// PX4's navigator takes a waypoint only within NAV_FW_ALT_RAD (10 m) of its
// height: a 15 deg climb to the end flown at 25 m/s over the ground is 79 m
// low where it is 119.4 m out, so the aircraft flies on, is turned back
// round the end by its guidance and takes it 10 m under it, after 69 m more
// of climb at 5.36 m/s (323 m more of flight).
TEST(L1Track, AWaypointIsTakenOnlyWithinTheAltitudeGate) {
  L1Flight f;
  f.ground_speed_m_per_s = 25.0;
  f.altitude_hold_m = f.l1_distance_m();
  f.max_climb_m_per_s = f.max_sink_m_per_s = 20.0 * std::tan(15.0 * kPi / 180.0);
  f.altitude_gate_m = 10.0;
  const double top = 100.0 + 1000.0 * std::tan(15.0 * kPi / 180.0);
  const std::vector<Vec3> climb = {Vec3(0, 0, 100), Vec3(1000, 0, top)};
  const FlownTrack gated = fly_l1(climb, f);
  ASSERT_TRUE(gated.reached_end);
  EXPECT_NEAR(gated.points.back().p_m.z(), top - 10.0, 0.2);
  double flown_m = 0;
  for (std::size_t k = 1; k < gated.points.size(); ++k) {
    flown_m += (gated.points[k].p_m - gated.points[k - 1].p_m).head<2>().norm();
  }
  EXPECT_NEAR(flown_m, (1000.0 - f.l1_distance_m()) + (top - 10.0 - 100.0 - 0.8 * 0.268 * 880.6) / 0.2144, 5.0);
  f.altitude_gate_m = std::numeric_limits<double>::infinity();  // no gate: taken 79 m low
  EXPECT_NEAR(fly_l1(climb, f).points.back().p_m.z(), 100.0 + 0.2144 * (1000.0 - f.l1_distance_m()), 0.5);
}

TEST(L1Track, AClimbLongerThanTheLegsIsGivenTheTimeItsRateNeeds) {
  // 1300 m up over 800 m at 5 m/s takes at least 260 s, more than three
  // times the 40 s of the legs and two minutes (240 s): the aircraft circles
  // round the end climbing until it is within the gate, and takes it
  L1Flight f;
  f.altitude_hold_m = f.l1_distance_m();
  f.max_climb_m_per_s = f.max_sink_m_per_s = 5.0;
  f.altitude_gate_m = 10.0;
  const std::vector<Vec3> climb = {Vec3(0, 0, 100), Vec3(800, 0, 1400)};
  const FlownTrack t = fly_l1(climb, f);
  ASSERT_TRUE(t.reached_end);
  EXPECT_GE(t.points.back().p_m.z(), 1390.0 - 1e-9);
  EXPECT_GT(static_cast<double>(t.points.size()) * f.step_s, 240.0);
}

}  // namespace
}  // namespace visvol::rt
