#include "rt/rope/path_check.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../../fields/terrains.hpp"
#include "climb_slope.hpp"
#include "fields/exact_visibility.hpp"

namespace visvol::rt {
namespace {

using namespace visvol::fields::testing;

// A flat plain at 100 m with a 60 m wall along post column 30 (10 m posts).
class WallTerrain : public ::testing::Test {
 protected:
  fields::Heightfield terrain = wall(64, 30, 60.0f);
  Vec3 post(double i, double j, double z) const { return {terrain.x_of(i), terrain.y_of(j), z}; }
  PathCheckSpec spec() const {
    PathCheckSpec s;
    s.envelope = *vehicle_preset("multirotor");
    s.envelope.clearance_m = 10;
    return s;
  }
};

TEST_F(WallTerrain, ObserverBehindTheWallDoesNotSeeALowPathAndSeesAHighOne) {
  PathCheckSpec s = spec();
  s.constraints = {{ConstraintKind::hidden_from, post(50, 32, 100), 2.0}};
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  // west of the wall, 20 m up: hidden behind 60 m of wall
  const PathCheck low = checker->check({post(5, 10, 120), post(5, 50, 120)});
  ASSERT_EQ(low.constraints.size(), 1u);
  EXPECT_TRUE(low.constraints[0].met);
  EXPECT_DOUBLE_EQ(low.constraints[0].satisfied_fraction, 1.0);
  EXPECT_TRUE(low.all_met);
  // 300 m up: seen everywhere
  const PathCheck high = checker->check({post(5, 10, 400), post(5, 50, 400)});
  EXPECT_FALSE(high.constraints[0].met);
  EXPECT_NEAR(high.constraints[0].satisfied_fraction, 0.0, 1e-12);
  EXPECT_FALSE(high.all_met);
  EXPECT_GT(high.violation, 0.9);
  EXPECT_EQ(high.flight_violation, 0.0) << "an observer's sight is no flight limit";
  ASSERT_EQ(high.unmet().size(), 1u);
  EXPECT_NE(high.unmet()[0].find("hidden-from"), std::string::npos);
  // 5 m up, under the 10 m clearance along all its length: a flight limit
  const PathCheck skim = checker->check({post(5, 10, 105), post(5, 50, 105)});
  EXPECT_TRUE(skim.constraints[0].met);
  EXPECT_NEAR(skim.flight_violation, 1.0, 1e-9);
  EXPECT_NEAR(skim.violation, skim.flight_violation, 1e-12);
}

TEST_F(WallTerrain, FractionsAreShareOfLengthAndAgreeWithR3) {
  PathCheckSpec s = spec();
  s.constraints = {{ConstraintKind::visible_to, post(50, 32, 100), 2.0}};
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok());
  // A path that climbs over the wall: the observer east of it sees only the part high enough.
  const std::vector<Vec3> path = {post(5, 32, 120), post(25, 32, 120), post(29, 32, 180), post(45, 32, 180)};
  const PathCheck c = checker->check(path);
  // the reference: R3 at 1 m steps, by length
  double seen = 0, total = 0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    const double len = (path[k] - path[k - 1]).norm();
    const int n = static_cast<int>(len);
    for (int q = 0; q < n; ++q) {
      const Vec3 p = path[k - 1] + (path[k] - path[k - 1]) * ((q + 0.5) / n);
      const Vec3 eye = s.constraints[0].eye_m();
      seen += fields::r3_visible(terrain, terrain.i_of(eye.x()), terrain.j_of(eye.y()), eye.z(), terrain.i_of(p.x()),
                                 terrain.j_of(p.y()), p.z(), 0.0) *
              len / n;
      total += len / n;
    }
  }
  EXPECT_NEAR(c.constraints[0].satisfied_fraction, seen / total, 0.02);
  EXPECT_NEAR(c.constraints[0].seen_m, seen, 0.02 * total);
  EXPECT_FALSE(c.constraints[0].met);
  EXPECT_NEAR(c.length_m, total, 1e-6);
}

TEST_F(WallTerrain, EnvelopeLimitsAreMeasuredPerSegmentAndSample) {
  PathCheckSpec s = spec();
  s.envelope.max_climb_deg = 20;
  s.envelope.max_descent_deg = 20;
  s.envelope.max_agl_m = 100;
  s.envelope.min_turn_radius_m = 50;
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok());
  // 100 m flat, then a 45 deg climb over 100 m, then a right angle turn
  const std::vector<Vec3> path = {post(5, 10, 120), post(15, 10, 120), post(25, 10, 220), post(25, 20, 220)};
  const PathCheck c = checker->check(path);
  auto limit = [&](const std::string& name) {
    for (const LimitResult& l : c.envelope)
      if (l.name == name) return l;
    ADD_FAILURE() << name;
    return LimitResult{};
  };
  EXPECT_NEAR(limit("max-climb").worst, 45.0, 1e-9);
  EXPECT_FALSE(limit("max-climb").met);
  // the climb is 141 m of 341 m
  EXPECT_NEAR(limit("max-climb").satisfied_fraction, 200.0 / (200.0 + 100.0 * std::sqrt(2.0)), 1e-9);
  EXPECT_TRUE(limit("max-descent").met);
  EXPECT_NEAR(limit("max-agl").worst, 120.0, 1e-6);
  EXPECT_FALSE(limit("max-agl").met);
  EXPECT_NEAR(limit("clearance").worst, 20.0, 1e-6);
  EXPECT_TRUE(limit("clearance").met);
  // the right angle between two 100 m (horizontal) segments whose other ends
  // do not turn: the arc may use all of both, 100 m
  EXPECT_NEAR(c.per_vertex[2].turn_radius_m, 100.0, 1e-6);
  EXPECT_TRUE(std::isinf(c.per_vertex[1].turn_radius_m));
  EXPECT_TRUE(limit("min-turn-radius").met);
}

// A requirement unmet by a hair never reads "holds on 1.000" in a report.
TEST(PathCheckReport, AFractionUnderOneIsNeverShownAsOne) {
  EXPECT_EQ(fraction_shown(1.0), 1.0);
  EXPECT_EQ(fraction_shown(0.9996), 0.999);
  EXPECT_EQ(fraction_shown(1.0 - 1e-15), 0.999);
  EXPECT_EQ(fraction_shown(0.5), 0.5);
  EXPECT_EQ(fraction_shown(0.0), 0.0);
  PathCheck c;
  LimitResult l;
  l.name = "min-turn-radius";
  l.unit = "m";
  l.limit = 80;
  l.satisfied_fraction = 0.9999;
  l.met = false;
  c.envelope.push_back(l);
  ASSERT_EQ(c.unmet().size(), 1u) << c.unmet()[0] << " / " << c.unmet().back();
  EXPECT_NE(c.unmet()[0].find("holds on 0.999 of the length"), std::string::npos) << c.unmet()[0];
}

// An unmet limit's worst value reads past the limit, never as the limit itself.
TEST(WorstDecimals, AnUnmetWorstNeverPrintsAsTheLimit) {
  LimitResult clearance;
  clearance.lower = true;
  clearance.limit = 30;
  clearance.worst = 29.96;
  clearance.met = false;
  EXPECT_EQ(worst_decimals(clearance), 2);
  clearance.worst = 29.0;
  EXPECT_EQ(worst_decimals(clearance), 1);
  clearance.worst = 29.9996;
  EXPECT_EQ(worst_decimals(clearance), 4);
  clearance.limit = 30.04;  // the limit is printed with the same decimals
  clearance.worst = 30.02;
  EXPECT_EQ(worst_decimals(clearance), 2);
  clearance.limit = 80;  // a turn radius unmet by its 1e-6 tolerance
  clearance.worst = 79.99999;
  EXPECT_EQ(worst_decimals(clearance), 5);
  LimitResult climb;  // an upper limit
  climb.limit = 10;
  climb.worst = 10.004;
  climb.met = false;
  EXPECT_EQ(worst_decimals(climb), 3);
  climb.met = true;
  EXPECT_EQ(worst_decimals(climb), 1);
}

TEST(TurnRadii, NeighbouringTurnsShareTheirSegment) {
  // a zig-zag of right angles every 100 m: each arc gets half of each segment
  const std::vector<Vec3> zig = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {200, 100, 0}, {200, 200, 0}};
  const std::vector<double> r = turn_radii_m(zig.data(), 5);
  EXPECT_TRUE(std::isinf(r[0]) && std::isinf(r[4]));
  EXPECT_NEAR(r[1], 50.0, 1e-9);  // its second segment is shared with vertex 2
  EXPECT_NEAR(r[2], 50.0, 1e-9);
  EXPECT_NEAR(r[3], 50.0, 1e-9);
  // a point inserted on a straight segment takes no share of it
  const std::vector<Vec3> split = {{0, 0, 0}, {100, 0, 0}, {100, 50, 0}, {100, 100, 0}, {200, 100, 0}};
  EXPECT_NEAR(turn_radii_m(split.data(), 5)[1], 50.0, 1e-9);
}

// A repeated waypoint or a climb on the spot is one spot of the horizontal
// track: the turn there is judged between the segments either side (a
// hairpin through a repeated waypoint is no longer unchecked), and a vertex a
// hair from its neighbour makes no hairpin of its own.
TEST(TurnRadii, RepeatedSpotsAreJudgedAsOneTurn) {
  const std::vector<Vec3> corner = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}};
  const double right_angle = turn_radii_m(corner.data(), 3)[1];
  EXPECT_NEAR(right_angle, 100.0, 1e-9);
  const std::vector<Vec3> climbing = {{0, 0, 0}, {100, 0, 30}, {100, 100, 90}};  // heights do not matter
  EXPECT_NEAR(turn_radii_m(climbing.data(), 3)[1], right_angle, 1e-9);
  for (const std::vector<Vec3>& run : {
           std::vector<Vec3>{{0, 0, 0}, {100, 0, 0}, {100, 0, 0}, {100, 100, 0}},          // repeated
           std::vector<Vec3>{{0, 0, 0}, {100, 0, 0}, {100, 0, 40}, {100, 100, 40}},        // climb on the spot
           std::vector<Vec3>{{0, 0, 0}, {100, 0, 0}, {100, 1e-8, 0}, {100, 100, 0}},       // a hair apart
           std::vector<Vec3>{{0, 0, 0}, {100, 0, 0}, {100.004, -0.004, 0}, {100, 100, 0}}  // under a centimetre
       }) {
    const std::vector<double> r = turn_radii_m(run.data(), 4);
    EXPECT_TRUE(std::isinf(r[0]) && std::isinf(r[3]));
    EXPECT_NEAR(r[1], right_angle, 1e-3) << run[2].transpose();
    EXPECT_NEAR(r[2], right_angle, 1e-3) << run[2].transpose();
  }
  // a hairpin through a repeated waypoint cannot be flown
  const std::vector<Vec3> hairpin = {{0, 0, 0}, {300, 0, 0}, {300, 0, 0}, {0, 10, 0}};
  const std::vector<double> r = turn_radii_m(hairpin.data(), 4);
  EXPECT_LT(r[1], 5.0);
  EXPECT_EQ(r[1], r[2]);
  // a run at an end is part of the end: no turn
  const std::vector<Vec3> ends = {{0, 0, 0}, {0, 0, 0}, {100, 0, 0}, {100, 0, 50}};
  for (double radius : turn_radii_m(ends.data(), 4)) EXPECT_TRUE(std::isinf(radius));
}

// Clearance and height above the terrain are exact along a segment, not
// only at the samples: a lone post between samples (a mast, a peak) is seen.
TEST(PathCheck, ClearanceIsExactBetweenSamples) {
  fields::Heightfield t = blank(5, 5, 30.0, 0.0f);
  t.at(2, 2) = 100.0f;  // a spike on a plain
  const Vec3 peak{t.x_of(2), t.y_of(2), 100.0};
  PathCheckSpec s;
  s.envelope = *vehicle_preset("multirotor");
  s.envelope.clearance_m = 30;
  s.envelope.max_agl_m = 119.5;
  s.sample_step_m = 7.5;  // samples a quarter post apart: the nearest 3.7 m from the peak
  const auto checker = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck c = checker->check({peak + Vec3(-55.0, 0, 20.0), peak + Vec3(55.0, 0, 20.0)});
  const LimitResult& clearance = c.envelope[0];
  ASSERT_EQ(clearance.name, "clearance");
  EXPECT_NEAR(clearance.worst, 20.0, 1e-9);  // over the peak itself
  EXPECT_FALSE(clearance.met);
  EXPECT_LT(clearance.satisfied_fraction, 1.0);
  EXPECT_LT(fraction_shown(clearance.satisfied_fraction), 1.0);
  // the highest point above the plain, at the ends, 120 m: over max-agl
  const LimitResult& agl = c.envelope[1];
  ASSERT_EQ(agl.name, "max-agl");
  EXPECT_NEAR(agl.worst, 120.0, 1e-9);
  EXPECT_FALSE(agl.met);
  // a path along the diagonal of cells: the lowest clearance inside a cell,
  // where the bilinear terrain is a curve along the path
  const Vec3 from{t.x_of(1), t.y_of(1), 60.0}, to{t.x_of(3), t.y_of(3) + 30.0, 60.0};
  const PathCheck d = checker->check({from, to});
  double lowest = 1e9;
  for (int k = 0; k <= 100000; ++k) {
    const Vec3 p = from + (to - from) * (k / 100000.0);
    lowest = std::min(lowest, p.z() - checker->ground_m(p.x(), p.y()));
  }
  EXPECT_NEAR(d.envelope[0].worst, lowest, 1e-6);
  // a segment far beyond the grid: the grid's lines only, at once
  const PathCheck far = checker->check({from, Vec3(1e12, -1e12, 60.0)});
  EXPECT_GT(far.length_m, 1e12);
}

// A fixed-wing flies by a corner on an arc inside it, at its min-turn-radius
// (or what the segments leave room for): a tall post there, away from both
// segments, fails the clearance; a multirotor turns on the corner and does not.
TEST(PathCheck, AFixedWingsArcInsideACornerIsChecked) {
  fields::Heightfield t = blank(40, 40, 10.0, 0.0f);
  // a block 20 to 30 m from the corner along both legs, 20 m from each: the
  // 80 m arc passes 33 m from the corner along its bisector, over it
  for (int i : {17, 18}) {
    for (int j : {22, 23}) t.at(i, j) = 150.0f;
  }
  const Vec3 corner{t.x_of(20), t.y_of(20), 110.0};
  const std::vector<Vec3> path = {corner + Vec3(-150, 0, 0), corner, corner + Vec3(0, -150, 0)};
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");  // 80 m turns, room for them on the 150 m legs
  s.envelope.max_climb_deg = s.envelope.max_descent_deg = 45;
  const auto fixed_wing = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(fixed_wing.ok()) << fixed_wing.status().message();
  const PathCheck flown_by = fixed_wing->check(path);
  EXPECT_FALSE(flown_by.envelope[0].met);
  EXPECT_LT(flown_by.envelope[0].worst, 30.0);
  EXPECT_LT(fraction_shown(flown_by.envelope[0].satisfied_fraction), 1.0);
  EXPECT_NEAR(flown_by.length_m, 300.0, 1e-9);                 // the arc takes no share of the length
  EXPECT_GT(fixed_wing->sample_count(path), 300.0 / 2.5 + 3);  // the arc's samples counted too
  // the same corner through a repeated waypoint
  const std::vector<Vec3> repeated = {path[0], corner, corner + Vec3(0, 0, 5), path[2]};
  EXPECT_FALSE(fixed_wing->check(repeated).envelope[0].met);
  // legs too short for 80 m: the arc at the radius they leave room for (a
  // straight neighbour's leg whole), inside the block's reach no more
  const std::vector<Vec3> short_legs = {corner + Vec3(-20, 0, 0), corner, corner + Vec3(0, -20, 0)};
  EXPECT_TRUE(fixed_wing->check(short_legs).envelope[0].met);
  s.envelope = *vehicle_preset("multirotor");
  s.envelope.clearance_m = 30;
  const auto multirotor = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(multirotor.ok());
  const PathCheck on_the_corner = multirotor->check(path);
  EXPECT_TRUE(on_the_corner.envelope[0].met) << on_the_corner.envelope[0].worst;
  EXPECT_NEAR(on_the_corner.envelope[0].worst, 110.0, 1e-9);
}

// A fixed-wing's autopilot takes each waypoint's height its acceptance
// radius early (100 m for the preset): a descent begun just past a ridge is
// flown over the ridge. The path holds 30 m over the ridge at its vertex;
// flown that way, it comes to under 6 m over it. Holding the height until
// the ridge is 100 m behind meets it; a multirotor reaching each waypoint
// has no such limit.
TEST(PathCheck, ADescentJustPastARidgeIsFlownOverTheRidge) {
  fields::Heightfield t = blank(60, 5, 10.0, 0.0f);
  for (int j = 0; j < 5; ++j) t.at(20, j) = 60.0f;
  const double run_m = 50.0 / std::tan(14.0 * M_PI / 180.0);  // 50 m down at 14 deg
  auto path_descending_from = [&](double i) {
    return std::vector<Vec3>{{t.x_of(2), t.y_of(2), 90.0},
                             {t.x_of(i), t.y_of(2), 90.0},
                             {t.x_of(i) + run_m, t.y_of(2), 40.0},
                             {t.x_of(57), t.y_of(2), 40.0}};
  };
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");
  s.envelope.max_wind_m_per_s = 0;  // calm: the radius as given
  ASSERT_EQ(s.envelope.acceptance_radius_m, 100.0);
  const auto checker = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck early = checker->check(path_descending_from(21));
  ASSERT_EQ(early.envelope.size(), 8u);  // and flown-clearance last
  const LimitResult& clearance = early.envelope[0];
  const LimitResult& flown = early.envelope[6];
  EXPECT_TRUE(clearance.met) << clearance.worst;  // 30 m over the ridge itself
  ASSERT_EQ(flown.name, "early-descent");
  EXPECT_FALSE(flown.met);
  // 90 m past the ridge, 90 tan(14 deg) m down: the ridge leaves the 100 m behind
  EXPECT_NEAR(flown.worst, 30.0 - 90.0 * std::tan(14.0 * M_PI / 180.0), 0.5);
  EXPECT_LT(flown.satisfied_fraction, 1.0);
  EXPECT_FALSE(early.all_met);
  const PathCheck held = checker->check(path_descending_from(31));
  EXPECT_TRUE(held.all_met) << held.envelope[6].worst;
  // a radius of 45 m: PX4 still ramps to 80 m (its loiter radius) before a
  // waypoint, ArduPlane to 45 m
  s.envelope.acceptance_radius_m = 45;
  const auto px4_45 = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(px4_45.ok());
  EXPECT_NEAR(px4_45->check(path_descending_from(21)).envelope[6].worst, 30.0 - 70.0 * std::tan(14.0 * M_PI / 180.0),
              0.5);
  s.envelope.autopilot = Autopilot::ardupilot;
  const auto ardupilot_45 = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(ardupilot_45.ok());
  EXPECT_NEAR(ardupilot_45->check(path_descending_from(21)).envelope[6].worst,
              30.0 - 35.0 * std::tan(14.0 * M_PI / 180.0), 0.5);
  s.envelope = *vehicle_preset("multirotor");
  s.envelope.clearance_m = 30;
  const auto multirotor = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(multirotor.ok());
  const PathCheck reached = multirotor->check(path_descending_from(21));
  EXPECT_EQ(reached.envelope.size(), 6u);
  EXPECT_TRUE(reached.all_met);
}

// PX4 ramps no altitude on a leg no longer than its acceptance radius: it
// steps to the leg's end height where it takes that waypoint, the radius
// before the leg's start. A leg of 80 m descending 20 m begins 70 m past a
// ridge: every point of it clears the ridge from 100 m (the old rule, at
// least 32.5 m), but its end height is flown from 120 m along, 30 m before
// the ridge, and comes 20 m over it. The same descent on a 120 m leg is
// ramped from the leg's start and clears it.
TEST(PathCheck, AShortLegIsFlownAtItsLowerHeightFromTheRadiusBeforeItsStart) {
  fields::Heightfield t = blank(60, 5, 10.0, 0.0f);
  for (int j = 0; j < 5; ++j) t.at(17, j) = 60.0f;  // 150 m along the track
  auto path_with_leg = [&](double end_i) {
    return std::vector<Vec3>{{t.x_of(2), t.y_of(2), 100.0},
                             {t.x_of(24), t.y_of(2), 100.0},
                             {t.x_of(end_i), t.y_of(2), 80.0},
                             {t.x_of(57), t.y_of(2), 80.0}};
  };
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");
  ASSERT_EQ(s.envelope.acceptance_radius_m, 100.0);
  s.envelope.max_wind_m_per_s = 0;  // calm: the preset's radius, 100 m
  const auto checker = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck stepped = checker->check(path_with_leg(32));
  ASSERT_EQ(stepped.envelope.size(), 8u);  // and flown-clearance last
  const LimitResult& flown = stepped.envelope[6];
  ASSERT_EQ(flown.name, "early-descent");
  EXPECT_TRUE(stepped.envelope[0].met);  // 40 m over the ridge as planned
  EXPECT_TRUE(stepped.envelope[4].met);  // 14 deg
  EXPECT_FALSE(flown.met);
  EXPECT_NEAR(flown.worst, 80.0 - 60.0, 1e-6);
  EXPECT_NEAR(flown.satisfied_fraction, 1.0 - 80.0 / 550.0, 0.02);  // the leg's samples
  // where: on the leg from vertex 1, the others' clear
  ASSERT_EQ(stepped.per_vertex.size(), 4u);
  EXPECT_NEAR(stepped.per_vertex[1].early_m, 20.0, 1e-6);
  EXPECT_GE(stepped.per_vertex[0].early_m, 30.0);
  EXPECT_GE(stepped.per_vertex[2].early_m, 30.0);
  EXPECT_TRUE(std::isinf(stepped.per_vertex[3].early_m));
  const PathCheck ramped = checker->check(path_with_leg(36));
  EXPECT_TRUE(ramped.all_met) << ramped.envelope[6].worst;
  // With 5 m/s of tailwind the autopilot switches 125 m out: the 120 m leg
  // is no longer ramped but stepped, its lower height over the ridge.
  PathCheckSpec windy = s;
  windy.envelope.max_wind_m_per_s = 5;
  const auto in_wind = PathChecker::create(t, nullptr, windy);
  ASSERT_TRUE(in_wind.ok()) << in_wind.status().message();
  const PathCheck stepped_in_wind = in_wind->check(path_with_leg(36));
  EXPECT_FALSE(stepped_in_wind.envelope[6].met);
  EXPECT_NEAR(stepped_in_wind.envelope[6].worst, 80.0 - 60.0, 1e-6);
  EXPECT_NEAR(stepped_in_wind.per_vertex[1].early_m, 20.0, 1e-6);
}

// A climb up a slope on legs between the acceptance radius (45 m) and PX4's
// hold (80 m): a leg's held stretch runs past its start, where the aircraft
// is already climbing to the leg's end; the start's height is held only up
// to the start, so a climb 31 m over a 14 degree slope meets it.
TEST(PathCheck, AClimbIsHeldAtItsStartsHeightOnlyUpToItsStart) {
  fields::Heightfield t = blank(80, 5, 10.0, 0.0f);
  const double slope = std::tan(14.0 * M_PI / 180.0);
  for (int i = 0; i < 80; ++i)
    for (int j = 0; j < 5; ++j) t.at(i, j) = static_cast<float>(10.0 * i * slope);
  std::vector<Vec3> climb;
  for (int i = 2; i <= 72; i += 7) climb.emplace_back(t.x_of(i), t.y_of(2), 10.0 * i * slope + 31.0);
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");
  s.envelope.max_wind_m_per_s = 0;  // calm: the radius as given
  s.envelope.acceptance_radius_m = 45;
  s.envelope.max_climb_deg = 15;
  const auto checker = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck c = checker->check(climb);
  EXPECT_TRUE(c.all_met) << c.envelope[6].name << " worst " << c.envelope[6].worst;
  // the same legs flown down the slope: each leg's lower end is held from
  // 45 m before the leg's start, over ground 115 m of slope above its own
  std::vector<Vec3> descent(climb.rbegin(), climb.rend());
  const PathCheck d = checker->check(descent);
  EXPECT_FALSE(d.envelope[6].met);
  EXPECT_NEAR(d.envelope[6].worst, 31.0 - (45.0 + 70.0) * slope, 1e-4);  // float terrain
}

TEST(PathCheck, AFixedWingsArcClimbsMoreSteeplyThanItsLegs) {
  const fields::Heightfield t = blank(60, 60, 10.0, 0.0f);
  // two 200 m legs climbing at 12 deg with a right angle between them: the
  // 80 m arc cuts 160 m of them and climbs their 34 m in 126 m, at 15.1 deg
  const double rise = 200.0 * std::tan(12.0 * M_PI / 180.0);
  const Vec3 corner{t.x_of(30), t.y_of(30), 300.0};
  const std::vector<Vec3> path = {corner + Vec3(-200, 0, -rise), corner, corner + Vec3(0, -200, rise)};
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");  // 80 m turns
  s.envelope.max_climb_deg = 14;
  s.envelope.max_descent_deg = 14;
  const auto fixed_wing = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(fixed_wing.ok()) << fixed_wing.status().message();
  const PathCheck flown = fixed_wing->check(path);
  const LimitResult& climb = flown.envelope[3];
  ASSERT_EQ(climb.name, "max-climb");
  EXPECT_FALSE(climb.met);
  EXPECT_NEAR(climb.worst, std::atan(2 * rise * 0.4 / (80 * M_PI / 2)) * 180 / M_PI, 1e-6);
  EXPECT_LT(fraction_shown(climb.satisfied_fraction), 1.0);
  EXPECT_TRUE(flown.envelope[4].met);  // max-descent: nothing descends
  // flown the other way, it descends as steeply
  const std::vector<Vec3> back(path.rbegin(), path.rend());
  EXPECT_FALSE(fixed_wing->check(back).envelope[4].met);
  EXPECT_TRUE(fixed_wing->check(back).envelope[3].met);
  // a multirotor turns on the corner: its legs at 12 deg are all it climbs
  s.envelope = *vehicle_preset("multirotor");
  s.envelope.max_climb_deg = 14;
  const auto multirotor = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(multirotor.ok());
  EXPECT_TRUE(multirotor->check(path).envelope[3].met);
  EXPECT_NEAR(multirotor->check(path).envelope[3].worst, 12.0, 1e-9);
}

// A notch one post wide in the wall: an observer far east sees, through it,
// a stretch of a path just west of the wall about 0.15 of a post long.
// Samples a quarter post apart (the step before) step over it and read the
// path hidden; the default step (a sixteenth) finds it (a skeptic's plan on
// Taunus was reported hidden while 13 m of it was in sight).
TEST_F(WallTerrain, AStretchInSightBetweenQuarterPostSamplesIsFound) {
  terrain.at(30, 32) = 100.0f;  // the notch
  PathCheckSpec s = spec();
  s.envelope.clearance_m = 1;
  s.constraints = {{ConstraintKind::hidden_from, post(60, 32, 100), 2.0}};
  // 40 posts along x = 28 at 104.35 m: quarter-post samples fall 0.125 post either side of the notch's line
  const std::vector<Vec3> path = {post(28, 12.125, 104.35), post(28, 52.125, 104.35)};
  // the reference: R3 every ten-thousandth of a post (1 mm) over the two posts around the notch
  const Vec3 eye = s.constraints[0].eye_m();
  double seen_m = 0;
  for (double y = 31.0; y < 33.0; y += 1e-4) {
    seen_m += fields::r3_visible(terrain, terrain.i_of(eye.x()), terrain.j_of(eye.y()), eye.z(), 28.0, y, 104.35, 0.0) *
              1e-4 * terrain.spacing_m;
  }
  ASSERT_GT(seen_m, 0.07 * terrain.spacing_m);  // a stretch in sight, shorter than a quarter post
  ASSERT_LT(seen_m, 0.25 * terrain.spacing_m);
  const auto by_default = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(by_default.ok());
  const PathCheck c = by_default->check(path);
  EXPECT_FALSE(c.constraints[0].met);
  EXPECT_NEAR(c.constraints[0].seen_m, seen_m, 0.0625 * terrain.spacing_m);
  s.sample_step_m = 0.25 * terrain.spacing_m;  // the quarter post: it misses the stretch
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s)->check(path).constraints[0].met);
}

TEST_F(WallTerrain, ObserversBelowTheTerrainOrOutsideAreRefusedByName) {
  PathCheckSpec s = spec();
  s.constraints = {{ConstraintKind::hidden_from, post(10, 10, 99.0), 2.0}};  // 1 m under the plain
  auto c = PathChecker::create(terrain, nullptr, s);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.status().message().find("--hidden-from"), std::string::npos);
  EXPECT_NE(c.status().message().find("the point is 1.00 m below the finest terrain (100.00 m there)"),
            std::string::npos)
      << c.status().message();
  // on the ground exactly: accepted
  s.constraints = {{ConstraintKind::hidden_from, post(10, 10, 100.0), 2.0}};
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s).ok());
  s.constraints = {{ConstraintKind::visible_to, post(-10, 10, 100.0), 2.0}};
  c = PathChecker::create(terrain, nullptr, s);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.status().message().find("--visible-to"), std::string::npos);
  s.constraints = {{ConstraintKind::visible_to, post(10, 10, std::nan("")), 2.0}};
  EXPECT_FALSE(PathChecker::create(terrain, nullptr, s).ok());
}

TEST_F(WallTerrain, OneEyeBothHiddenFromAndVisibleToIsRefused) {
  // no path can meet both: refused as input, not planned and reported unmet
  PathCheckSpec s = spec();
  s.constraints = {{ConstraintKind::hidden_from, post(10, 10, 100.0), 2.0},
                   {ConstraintKind::visible_to, post(10, 10, 100.0), 2.0}};
  const auto c = PathChecker::create(terrain, nullptr, s);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), Errc::invalid_argument);
  EXPECT_NE(c.status().message().find("--hidden-from and --visible-to name the same eye"), std::string::npos)
      << c.status().message();
  // the same spot seen from another height is a different eye
  s.constraints[1].eye_height_m = 30.0;
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s).ok());
}

TEST_F(WallTerrain, PlanningBoundsAreAFractionOfLength) {
  PathCheckSpec s = spec();
  s.planning_bounds = fields::Bounds2D{terrain.x_of(10), terrain.y_of(50), terrain.x_of(50), terrain.y_of(10)};
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok());
  const PathCheck c = checker->check({post(0, 20, 130), post(20, 20, 130)});  // half outside
  EXPECT_FALSE(c.inside_planning_bounds);
  EXPECT_NEAR(c.inside_bounds_fraction, 0.5, 0.02);
  EXPECT_FALSE(c.all_met);
}

TEST_F(WallTerrain, APathOnTheBoundsEdgeIsInsideAsWrittenAndReadBack) {
  // A plan's path on the edge of the bounds, written to a .plan and read
  // back, moves by a fraction of a millimetre (read as 5.5% outside before);
  // a centimetre is the tolerance, as for heights.
  PathCheckSpec s = spec();
  const fields::Bounds2D b{terrain.x_of(10), terrain.y_of(50), terrain.x_of(50), terrain.y_of(10)};
  s.planning_bounds = b;
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok());
  auto along_the_edge = [&](double out_m) {
    Vec3 a = post(20, 10, 130), c = post(40, 10, 130);
    a.y() = c.y() = b.ymax_m + out_m;
    return checker->check({post(20, 20, 130), a, c, post(40, 20, 130)});
  };
  EXPECT_TRUE(along_the_edge(0.0).inside_planning_bounds);
  EXPECT_TRUE(along_the_edge(3e-5).inside_planning_bounds);
  const PathCheck out = along_the_edge(0.02);
  EXPECT_FALSE(out.inside_planning_bounds);
  EXPECT_LT(out.inside_bounds_fraction, 0.9);
}

// A plain at 100 m (5 m posts) and a right-angle corner 30 m over it, legs of
// 700 and 800 m; a rock 40 m high (posts 6 to 8 inside the corner, 42 m from
// it along the bisector at the nearest) where the legs and the 80 m arc do
// not pass, and PX4 flies.
class RockInsideACorner : public ::testing::Test {
 protected:
  void SetUp() override {
    terrain = fields::testing::blank(200, 200, 5.0, 100.0f);
    for (int j = 46; j <= 48; ++j) {
      for (int i = 26; i <= 28; ++i) terrain.at(i, j) = 140.0f;
    }
  }
  Vec3 post(double i, double j, double z) const { return {terrain.x_of(i), terrain.y_of(j), z}; }
  std::vector<Vec3> corner() const { return {post(20, 180, 130), post(20, 40, 130), post(180, 40, 130)}; }
  fields::Heightfield terrain;
};

TEST_F(RockInsideACorner, ThePx4FlightCutsTheCornerOverTheRockTheArcMisses) {
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");  // 20 m/s, 100 m radius, 5 m/s of wind
  s.constraints = {{ConstraintKind::hidden_from, post(190, 190, 100), 2.0}};
  const auto checker = PathChecker::create(terrain, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck c = checker->check(corner());
  ASSERT_EQ(c.envelope.size(), 8u);
  EXPECT_EQ(c.envelope[0].name, "clearance");
  EXPECT_TRUE(c.envelope[0].met) << "the legs and the arc clear the rock";
  const LimitResult& flown = c.envelope[7];
  EXPECT_EQ(flown.name, "flown-clearance");
  EXPECT_FALSE(flown.met);
  EXPECT_LT(flown.worst, 0.0);
  EXPECT_FALSE(c.all_met);
  // (the observer across the plain sees it all: the report's constraint)
  ASSERT_EQ(c.unmet().size(), 2u);
  EXPECT_NE(c.unmet()[1].find("flown-clearance 30.0 m: worst -10.0 m, holds on 0.98"), std::string::npos)
      << c.unmet()[1];
  EXPECT_NE(c.unmet()[1].find("of the flown length"), std::string::npos) << c.unmet()[1];
  // the same path 50 m higher clears the rock however it is flown
  std::vector<Vec3> high = corner();
  for (Vec3& p : high) p.z() += 50;
  const PathCheck above = checker->check(high);
  EXPECT_TRUE(above.envelope[7].met) << above.envelope[7].worst;
  EXPECT_NEAR(above.envelope[7].worst, 40.0, 1e-3);  // over the rock's top
  const std::vector<FlownCheck> flights = checker->fly(corner());
  ASSERT_EQ(flights.size(), 2u);
  EXPECT_DOUBLE_EQ(flights[0].ground_speed_m_per_s, 20.0);
  EXPECT_DOUBLE_EQ(flights[0].switch_distance_m, 100.0);  // the radius
  // PX4's L1 distance (0.75 x 20 s x V / pi) where it is the larger: 95.5 m
  // at 20 m/s, 119.4 m at 25
  EXPECT_NEAR(flights[0].altitude_hold_m, 95.49, 0.01);
  EXPECT_DOUBLE_EQ(flights[1].ground_speed_m_per_s, 25.0);
  EXPECT_NEAR(flights[1].switch_distance_m, 119.37, 0.01);
  EXPECT_NEAR(flights[1].altitude_hold_m, 119.37, 0.01);
  for (const FlownCheck& f : flights) {
    EXPECT_TRUE(f.reached_end);
    EXPECT_LT(f.least_clearance_m, 0.0) << "into the rock";
    EXPECT_LT(f.clearance_fraction, 1.0);
    EXPECT_GT(f.clearance_fraction, 0.9);
    // the rock is where it flies low
    EXPECT_LT((f.least_at_m - post(27, 47, 0)).head<2>().norm(), 15.0);
    ASSERT_EQ(f.constraint_fractions.size(), 1u);
    // shorter than the legs' 1500 m by the cut corner and the switch distance at the end
    EXPECT_GT(f.length_m, 1500.0 - f.switch_distance_m - 100.0);
    EXPECT_LT(f.length_m, 1500.0 - f.switch_distance_m);
  }
  // 31.6 m off the legs at the deepest in still air (the independent
  // simulation of l1_track_test), farther in the tailwind
  EXPECT_NEAR(flights[0].max_off_path_m, 31.6, 1.0);
  EXPECT_GT(flights[1].max_off_path_m, flights[0].max_off_path_m + 5.0);
}

TEST_F(RockInsideACorner, OnlyAPx4FixedWingThatSwitchesEarlyIsFlown) {
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");
  s.envelope.max_wind_m_per_s = 0;  // still air only
  EXPECT_EQ(PathChecker::create(terrain, nullptr, s)->fly(corner()).size(), 1u);
  s.envelope.acceptance_radius_m = 0;  // every waypoint reached
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s)->fly(corner()).empty());
  s.envelope = *vehicle_preset("fixed-wing");
  s.envelope.autopilot = Autopilot::ardupilot;
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s)->fly(corner()).empty());
  s.envelope = *vehicle_preset("multirotor");
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s)->fly(corner()).empty());
  s.envelope = *vehicle_preset("fixed-wing");
  std::vector<Vec3> bad = corner();
  bad[1].x() = std::nan("");
  EXPECT_TRUE(PathChecker::create(terrain, nullptr, s)->fly(bad).empty());
}

// A climb of 104 m over 400 m (14.6 deg, inside the preset's 15) up a slope
// that follows it 20 m behind, 35.2 m under the legs. PX4 climbs at its
// airspeed's rate, 5.36 m/s: 0.268 m a metre in still air, and it follows
// the legs; 0.214 m a metre at 25 m/s over the ground with the wind behind
// it, so it reaches the top 18.4 m low, 16.9 m over the ground (by hand, at
// the check's 50 Hz; the planned heights alone read 35.2 m there).
TEST(ClimbInATailwind, PX4FallsBehindAClimbTheLegsMakeWithinTheLimit) {
  const testing::ClimbSlope slope;
  const fields::Heightfield& t = slope.terrain;
  const std::vector<Vec3>& climb = slope.path;
  PathCheckSpec s;
  s.envelope = *vehicle_preset("fixed-wing");  // 20 m/s, 15 deg, 5 m/s of wind
  const auto checker = PathChecker::create(t, nullptr, s);
  ASSERT_TRUE(checker.ok()) << checker.status().message();
  const PathCheck c = checker->check(climb);
  for (const LimitResult& l : c.envelope) {
    if (l.name == kFlownClearance) {
      EXPECT_FALSE(l.met);
      EXPECT_NEAR(l.worst, 16.9, 0.3);
    } else {
      EXPECT_TRUE(l.met) << l.name << " worst " << l.worst;
    }
  }
  // reported: still air and the strongest tailwind, the lowest of the 11
  // (the faster over the ground, the less height a metre)
  const std::vector<FlownCheck> flights = checker->fly(climb);
  ASSERT_EQ(flights.size(), 2u);
  EXPECT_EQ(flights[0].ground_speed_m_per_s, 20.0);
  EXPECT_EQ(flights[1].ground_speed_m_per_s, 25.0);
  // still air: at the legs or above (30 m at the start, 35.2 m along the climb)
  EXPECT_GE(flights[0].least_clearance_m, 30.0 - 1e-6);
  EXPECT_GE(flights[0].clearance_fraction, 1.0);
  EXPECT_NEAR(flights[1].least_clearance_m, 16.9, 0.3);
  EXPECT_NEAR(flights[1].least_at_m.x(), t.x_of(180), 10.0);  // at the top of the climb
}

TEST(Px4Flights, EveryHalfMetreASecondFromStillAirToTheStrongestTailwind) {
  // the least clearance is not always at either end: an independent
  // simulation flew a SF North mission 30.57 m over the ground at 20 m/s and
  // 30.28 m at 25, and 29.92 m at 22.5
  VehicleEnvelope e = *vehicle_preset("fixed-wing");  // 20 m/s, 5 m/s of wind
  std::vector<L1Flight> f = px4_flights(e);
  ASSERT_EQ(f.size(), 11u);
  for (std::size_t i = 0; i < f.size(); ++i) {
    EXPECT_DOUBLE_EQ(f[i].ground_speed_m_per_s, 20.0 + 0.5 * static_cast<double>(i));
    // PX4 at that ground speed: the hold the L1 distance or 80 m, the larger
    EXPECT_DOUBLE_EQ(f[i].altitude_hold_m, std::max(f[i].l1_distance_m(), kPx4LoiterRadiusM));
    EXPECT_DOUBLE_EQ(f[i].max_climb_m_per_s, f[0].max_climb_m_per_s);  // at cruise airspeed
  }
  EXPECT_NEAR(f[5].altitude_hold_m, 107.4, 0.05);  // 22.5 m/s
  e.max_wind_m_per_s = 1.2;                        // 3 steps of 0.4 m/s
  f = px4_flights(e);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_DOUBLE_EQ(f[3].ground_speed_m_per_s, 21.2);
  e.max_wind_m_per_s = 100;  // at most kMaxPx4Flights
  EXPECT_EQ(px4_flights(e).size(), static_cast<std::size_t>(kMaxPx4Flights));
  e.max_wind_m_per_s = 0;  // still air only
  EXPECT_EQ(px4_flights(e).size(), 1u);
}

}  // namespace
}  // namespace visvol::rt
