#include "rt/rope/envelope_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "../../fields/terrains.hpp"
#include "climb_slope.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/point_hull.hpp"

namespace visvol::rt {
namespace {

using namespace visvol::fields::testing;

// The checker's judgement of a path on terrain t for envelope e (sight
// lines and limits on the terrain), not the fit's own flag.
PathCheck judge_on(const fields::Heightfield& t, const VehicleEnvelope& e, const std::vector<Vec3>& path) {
  PathCheckSpec s;
  s.envelope = e;
  const auto checker = PathChecker::create(t, nullptr, s);
  EXPECT_TRUE(checker.ok()) << checker.status().message();
  return checker.ok() ? checker->check(path) : PathCheck{};
}

// Every envelope limit of c met; else the unmet ones and their worst values.
::testing::AssertionResult every_limit_met(const PathCheck& c) {
  std::string unmet;
  for (const LimitResult& l : c.envelope) {
    if (!l.met) unmet += " " + l.name + " worst " + std::to_string(l.worst);
  }
  if (unmet.empty()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "unmet:" << unmet;
}

// The fitted paths are judged by the checker (sight lines and limits on the
// terrain), not by the fit's own flag.
class FitOnRelief : public ::testing::Test {
 protected:
  fields::Heightfield terrain = fractal(96, 7, 30.0, 150.0);
  // The fit's band at each point: the ground behind a point (an acceptance
  // radius) has its own tests (FitEarlyDescent).
  VehicleEnvelope envelope() const {
    VehicleEnvelope e;  // fixed-wing: 15 deg, 80 m turns
    e.acceptance_radius_m = 0;
    e.clearance_m = 40;
    e.max_agl_m = 400;
    return e;
  }
  Vec3 at(double i, double j, double agl) const {
    return {terrain.x_of(i), terrain.y_of(j), fields::bilinear_height(terrain, i, j) + agl};
  }
  static EnvelopeFitSpec spec_of(const VehicleEnvelope& e) {
    EnvelopeFitSpec s;
    s.envelope = e;
    return s;
  }
  PathCheck judge(const std::vector<Vec3>& path, const VehicleEnvelope& e) const { return judge_on(terrain, e, path); }
};

// A block inside a corner, under the 80 m arc a fixed-wing flies by it on
// and away from both legs: the fit raises the corner until the arc clears
// it (the arc follows 0.87 of the corner's move on 600 m legs), and the
// checker agrees; on legs the arc spans, no corner height can, and the fit
// says so in its passes.
TEST(FitArcs, TheCornerRisesUntilItsArcClearsTheTerrain) {
  fields::Heightfield t = blank(100, 100, 10.0, 0.0f);
  for (int i : {67, 68}) {
    for (int j : {22, 23}) t.at(i, j) = 150.0f;
  }
  const Vec3 corner{t.x_of(70), t.y_of(20), 110.0};
  VehicleEnvelope e;  // fixed-wing: 15 deg, 80 m turns, clearance 30 m
  EnvelopeFitSpec spec;
  spec.envelope = e;
  PathCheckSpec check_spec;
  check_spec.envelope = e;
  const auto checker = PathChecker::create(t, nullptr, check_spec);
  ASSERT_TRUE(checker.ok());
  const std::vector<Vec3> path = {corner + Vec3(-600, 0, 0), corner, corner + Vec3(0, -600, 0)};
  ASSERT_FALSE(checker->check(path).envelope[0].met);  // the arc passes over the block
  const EnvelopeFit fit = fit_to_envelope(path, spec, t);
  ASSERT_TRUE(fit.feasible);
  const PathCheck c = checker->check(fit.path);
  EXPECT_TRUE(every_limit_met(c));
  EXPECT_GE(c.envelope[0].worst, e.clearance_m);
  // 100 m legs: the 80 m arc's heights follow the fixed ends, not the corner
  const std::vector<Vec3> short_legs = {corner + Vec3(-100, 0, 0), corner, corner + Vec3(0, -100, 0)};
  const EnvelopeFit pinned = fit_to_envelope(short_legs, spec, t);
  EXPECT_FALSE(pinned.feasible && !checker->check(pinned.path).all_met);
}

// A rock inside a corner where neither the legs nor the 80 m arc pass but
// PX4 cuts the corner over it (path_check_test's RockInsideACorner): the
// fit raises the legs flown there until both flights clear it, and the
// checker agrees; nothing else about the path changes.
TEST(FitFlights, TheLegsRiseUntilThePx4FlightsClearARockInsideTheCorner) {
  fields::Heightfield t = blank(200, 200, 5.0, 100.0f);
  for (int j = 46; j <= 48; ++j) {
    for (int i = 26; i <= 28; ++i) t.at(i, j) = 140.0f;
  }
  const std::vector<Vec3> path = {
      {t.x_of(20), t.y_of(180), 135.0}, {t.x_of(20), t.y_of(40), 135.0}, {t.x_of(180), t.y_of(40), 135.0}};
  EnvelopeFitSpec spec;
  spec.envelope = *vehicle_preset("fixed-wing");  // 100 m, 5 m/s of wind
  const PathCheck before = judge_on(t, spec.envelope, path);
  ASSERT_EQ(before.envelope.back().name, "flown-clearance");
  ASSERT_FALSE(before.envelope.back().met);
  const EnvelopeFit fit = fit_to_envelope(path, spec, t);
  const PathCheck c = judge_on(t, spec.envelope, fit.path);
  EXPECT_TRUE(every_limit_met(c));
  ASSERT_TRUE(fit.feasible);
  EXPECT_GE(c.envelope.back().worst, spec.envelope.clearance_m);
  // over the rock's 140 m and the clearance, not far over it
  double highest = 0;
  for (const Vec3& p : fit.path) highest = std::max(highest, p.z());
  EXPECT_GE(highest, 140.0 + spec.envelope.clearance_m);
  EXPECT_LT(highest, 140.0 + spec.envelope.clearance_m + 5.0);
  EXPECT_EQ(fit.path.front(), path.front());
  EXPECT_EQ(fit.path.back(), path.back());
}

// Ends exactly at the clearance over a plain (a user's take-off and landing
// heights): the fit asks the legs beside them for only what the ends have
// of its margin, so the corner stays where it was. It was raised pass after
// pass, to 282 m, and the fit said no path held the envelope.
TEST(FitEnds, AnEndExactlyAtTheClearanceAsksNoMarginBesideIt) {
  for (const char* vehicle : {"fixed-wing", "multirotor"}) {
    SCOPED_TRACE(vehicle);
    const fields::Heightfield t = blank(200, 200, 5.0, 100.0f);
    EnvelopeFitSpec spec;
    spec.envelope = *vehicle_preset(vehicle);
    const double z = 100.0 + spec.envelope.clearance_m;
    for (const double below_m : {0.0, 0.3}) {  // the ends short of the fit's 0.5 m margin, or of the clearance
      const std::vector<Vec3> path = {
          {t.x_of(20), t.y_of(180), z - below_m}, {t.x_of(20), t.y_of(40), z}, {t.x_of(180), t.y_of(40), z - below_m}};
      const EnvelopeFit fit = fit_to_envelope(path, spec, t);
      double highest = 0;
      for (const Vec3& p : fit.path) highest = std::max(highest, p.z());
      EXPECT_EQ(fit.path.front(), path.front());
      EXPECT_EQ(fit.path.back(), path.back());
      EXPECT_LT(highest, z + 2 * spec.margin_m) << "below " << below_m;  // was 282 m
      if (below_m == 0.0) {
        EXPECT_TRUE(fit.feasible);
        EXPECT_TRUE(every_limit_met(judge_on(t, spec.envelope, fit.path)));
      } else {
        EXPECT_FALSE(fit.feasible);  // the ends under the clearance: the check's to report
      }
    }
  }
}

// An end that lacks only a hull's 5 m margin (a visible-to point's hull at
// 128 m over a 100 m plain, the end at the 30 m clearance) is no licence to
// pass under the clearance over a knoll beside it: the leg clears the knoll
// (a skeptic's case; the fit had called a path 2 m under it feasible).
TEST(FitEnds, AHullsMarginAnEndLacksNeverTakesTheLegUnderTheClearance) {
  fields::Heightfield t = blank(200, 200, 5.0, 100.0f);
  for (int j = 160; j <= 168; ++j) {
    for (int i = 16; i <= 24; ++i) t.at(i, j) = 104.0f;  // 70 m along the first leg
  }
  PointHull hull;  // seen from everywhere above 128 m
  hull.nx = hull.ny = 2;
  hull.origin_x = t.x_of(0);
  hull.origin_y = t.y_of(0);
  hull.spacing_m = 199 * t.spacing_m;
  hull.height_m.assign(4, 128.0f);
  EnvelopeFitSpec spec;
  spec.envelope = *vehicle_preset("multirotor");
  spec.above = {&hull};
  const double z = 100.0 + spec.envelope.clearance_m;
  const std::vector<Vec3> path = {
      {t.x_of(20), t.y_of(180), z}, {t.x_of(20), t.y_of(40), 134.0}, {t.x_of(180), t.y_of(40), 134.0}};
  const EnvelopeFit fit = fit_to_envelope(path, spec, t);
  EXPECT_TRUE(fit.feasible);
  EXPECT_TRUE(every_limit_met(judge_on(t, spec.envelope, fit.path)));
}

// And ends exactly at a ceiling (showing under --max-agl): the legs beside
// them are not pushed down after the margin the ends do not keep.
TEST(FitEnds, AnEndExactlyAtTheCeilingAsksNoMarginBesideIt) {
  const fields::Heightfield t = blank(200, 200, 5.0, 100.0f);
  EnvelopeFitSpec spec;
  spec.envelope = *vehicle_preset("fixed-wing");
  spec.envelope.max_agl_m = 150.0;
  const double z = 100.0 + spec.envelope.max_agl_m;
  const std::vector<Vec3> path = {
      {t.x_of(20), t.y_of(180), z}, {t.x_of(20), t.y_of(40), z}, {t.x_of(180), t.y_of(40), z}};
  const EnvelopeFit fit = fit_to_envelope(path, spec, t);
  EXPECT_TRUE(fit.feasible);
  double lowest = 1e9;
  for (const Vec3& p : fit.path) lowest = std::min(lowest, p.z());
  EXPECT_GT(lowest, z - 2 * spec.margin_m);
  EXPECT_TRUE(every_limit_met(judge_on(t, spec.envelope, fit.path)));
}

TEST_F(FitOnRelief, AStraightLineThroughTheHillsBecomesFlyable) {
  const std::vector<Vec3> straight = {at(5, 5, 60), at(90, 88, 60)};
  ASSERT_FALSE(judge(straight, envelope()).all_met);  // it cuts through the relief
  const EnvelopeFit fit = fit_to_envelope(straight, spec_of(envelope()), terrain);
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path, envelope());
  EXPECT_TRUE(every_limit_met(c));
  EXPECT_EQ(fit.path.front(), straight.front());
  EXPECT_EQ(fit.path.back(), straight.back());
}

TEST_F(FitOnRelief, RandomWigglesBecomeFlyableAndKeepTheirEnds) {
  // property: any path between valid ends, fitted, meets every limit (when the fit says it could)
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(8, 88), h(-200, 600);
  int feasible = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> path = {at(u(rng), u(rng), 100)};
    for (int k = 0; k < 12; ++k) {
      const double i = u(rng), j = u(rng);
      path.push_back({terrain.x_of(i), terrain.y_of(j), fields::bilinear_height(terrain, i, j) + h(rng)});
    }
    path.push_back(at(u(rng), u(rng), 100));
    const EnvelopeFit fit = fit_to_envelope(path, spec_of(envelope()), terrain);
    EXPECT_EQ(fit.path.front(), path.front());
    EXPECT_EQ(fit.path.back(), path.back());
    for (const Vec3& v : fit.path) ASSERT_TRUE(v.allFinite());
    if (!fit.feasible) continue;
    ++feasible;
    const PathCheck c = judge(fit.path, envelope());
    for (const LimitResult& l : c.envelope)
      EXPECT_TRUE(l.met) << "trial " << trial << ": " << l.name << " worst " << l.worst;
  }
  EXPECT_GE(feasible, 15);
}

TEST_F(FitOnRelief, ACeilingAndAnAltitudeLimitHold) {
  VehicleEnvelope e = envelope();
  e.max_agl_m = 120;
  e.max_altitude_m = at(48, 48, 0).z() + 300;
  std::vector<Vec3> high = {at(10, 10, 100)};
  for (int k = 1; k < 10; ++k) high.push_back(at(10 + 8 * k, 10 + 8 * k, 2000));  // far too high
  high.push_back(at(85, 85, 100));
  if (high.back().z() > e.max_altitude_m) GTEST_SKIP() << "end above the altitude limit on this relief";
  const EnvelopeFit fit = fit_to_envelope(high, spec_of(e), terrain);
  const PathCheck c = judge(fit.path, e);
  for (const LimitResult& l : c.envelope) EXPECT_TRUE(l.met || !fit.feasible) << l.name << " worst " << l.worst;
  EXPECT_TRUE(fit.feasible);
}

TEST_F(FitOnRelief, TightTurnsAreOpenedUp) {
  VehicleEnvelope e = envelope();
  e.min_turn_radius_m = 150;
  // a zig-zag of 90 degree corners every 120 m
  std::vector<Vec3> zig;
  for (int k = 0; k <= 16; ++k) zig.push_back(at(20 + 4 * k, 40 + ((k % 2) ? 4 : 0), 150));
  const EnvelopeFit fit = fit_to_envelope(zig, spec_of(e), terrain);
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path, e);
  EXPECT_TRUE(every_limit_met(c));
}

// A narrow band of heights over rough terrain makes the fit split segments
// to hold it between vertices; each split shortens the segments beside a
// turn and with them the fillet it may use. The turns must still fit.
TEST_F(FitOnRelief, TurnsHoldWhereTheHeightsSplitSegments) {
  VehicleEnvelope e = envelope();
  e.clearance_m = 40;
  e.max_agl_m = 70;
  e.min_turn_radius_m = 80;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> turn(-0.5, 0.5);  // rad between segments
  int feasible = 0, split = 0;
  for (int trial = 0; trial < 12; ++trial) {
    // a meander of 10 segments of 8 posts (240 m) from the west edge
    double i = 6, j = 20 + 5 * trial, heading = 0;
    std::vector<Vec3> path = {at(i, j, 48)};
    for (int k = 0; k < 10; ++k) {
      heading += turn(rng);
      i += 8 * std::cos(heading);
      j = std::clamp(j + 8 * std::sin(heading), 5.0, 90.0);
      path.push_back(at(i, j, 48));
    }
    const EnvelopeFit fit = fit_to_envelope(path, spec_of(e), terrain);
    split += fit.path.size() > path.size();
    if (!fit.feasible) continue;
    ++feasible;
    const PathCheck c = judge(fit.path, e);
    for (const LimitResult& l : c.envelope)
      EXPECT_TRUE(l.met) << "trial " << trial << ": " << l.name << " worst " << l.worst;
  }
  EXPECT_GE(split, 4) << "the band should make the fit split segments";
  // 10 of 12 when a split could fall at a segment's end and the turns were
  // not opened again (trial 0 ended with a 22 m turn); the one left is a
  // band the slopes cannot hold
  EXPECT_GE(feasible, 11);
}

TEST_F(FitOnRelief, StaysInsideThePlanningBounds) {
  const fields::Bounds2D b{terrain.x_of(10), terrain.y_of(80), terrain.x_of(80), terrain.y_of(10)};
  std::vector<Vec3> wide = {at(20, 20, 100), at(2, 50, 100), at(70, 94, 100), at(60, 60, 100)};
  EnvelopeFitSpec spec = spec_of(envelope());
  spec.planning_bounds = b;
  const EnvelopeFit fit = fit_to_envelope(wide, spec, terrain);
  for (const Vec3& v : fit.path) EXPECT_TRUE(b.contains(v.x(), v.y())) << v.transpose();
}

TEST_F(FitOnRelief, ABandItCannotHoldIsNeverSplitBelowAMetre) {
  // an end 1 m above the ground under a 40 m clearance: no height of the
  // first segment holds the band, however it is split (before, the fit split
  // it at a quarter again and again, down to millimetres: slopes a written
  // file's rounding turns past the limits, hundreds of waypoints on one spot)
  const std::vector<Vec3> low_start = {at(20, 20, 1), at(60, 50, 60)};
  for (double turn_m : {0.0, 80.0}) {
    VehicleEnvelope e = envelope();
    e.min_turn_radius_m = turn_m;
    const EnvelopeFit fit = fit_to_envelope(low_start, spec_of(e), terrain);
    EXPECT_FALSE(fit.feasible);
    EXPECT_LE(fit.path.size(), 40u) << "the splits stop where they no longer help (72 points before)";
    for (std::size_t i = 0; i + 1 < fit.path.size(); ++i) {
      const Vec3 d = fit.path[i + 1] - fit.path[i];
      EXPECT_GE(std::hypot(d.x(), d.y()), 1.0) << "segment " << i << " of " << fit.path.size() - 1;
    }
  }
}

// A band 14 m wide over 150 m of relief, on legs 300 m long: the fit needs
// hundreds of vertices between them. It split one segment a pass and ran
// out of passes, leaving a multirotor's plans over their max-agl between
// vertices (81.2 m against 80 m); every segment that needs one now gets its
// vertex in the same pass.
TEST_F(FitOnRelief, HundredsOfSplitsFitInItsPasses) {
  VehicleEnvelope e = *vehicle_preset("multirotor");
  e.clearance_m = 30;
  e.max_agl_m = 45;
  std::vector<Vec3> path;
  for (int k = 0; k <= 24; ++k) path.push_back(at(6 + 3.5 * k, k % 2 ? 30 : 60, 38));
  EnvelopeFitSpec spec = spec_of(e);
  spec.max_points = 2000;  // room for what the band needs: the passes are what is tested
  const EnvelopeFit fit = fit_to_envelope(path, spec, terrain);
  EXPECT_GT(fit.path.size(), 250u) << "the band needs hundreds of vertices";
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path, e);
  EXPECT_TRUE(every_limit_met(c));
}

// An observer's hull is a wish, the envelope a limit: a visible-to hull far
// over the ceiling pinned every vertex to the ceiling, so the last leg fell
// 21 m in 5 m to an end lower down (77 degrees under a 45 degree limit).
// Where both cannot hold, the fit holds the envelope.
TEST_F(FitOnRelief, TheEnvelopeHoldsWhereAnObserversHullCannot) {
  VehicleEnvelope e = *vehicle_preset("multirotor");
  e.clearance_m = 30;
  e.max_agl_m = 80;
  PointHull sky;  // seen only from far above the ceiling, everywhere
  sky.nx = sky.ny = 2;
  sky.origin_x = terrain.x_of(0);
  sky.origin_y = terrain.y_of(0);
  sky.spacing_m = 95 * terrain.spacing_m;
  sky.height_m.assign(4, 1.0e4f);
  EnvelopeFitSpec spec = spec_of(e);
  spec.above = {&sky};
  const std::vector<Vec3> path = {at(10, 10, 40), at(30, 40, 60), at(50, 50, 60), at(70, 60, 40)};
  const EnvelopeFit fit = fit_to_envelope(path, spec, terrain);
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path, e);
  EXPECT_TRUE(every_limit_met(c));
  EXPECT_EQ(fit.path.back(), path.back());
}

// A fixed-wing's autopilot takes each waypoint's height 100 m early (its
// acceptance radius): the fit holds the height over a ridge until the ridge
// is that far behind, so the path flown that way clears it too; fitted for
// an autopilot that reaches each waypoint, the same path descends at once
// and is flown over the ridge.
class FitEarlyDescent : public ::testing::Test {
 protected:
  FitEarlyDescent() {
    for (int j = 0; j < 5; ++j) t.at(20, j) = 60.0f;  // a ridge across the track
  }
  Vec3 at(double i, double z) const { return {t.x_of(i), t.y_of(2), z}; }
  PathCheck judge(const std::vector<Vec3>& path) const { return judge_on(t, fixed_wing, path); }
  fields::Heightfield t = blank(60, 5, 10.0, 0.0f);
  VehicleEnvelope fixed_wing = *vehicle_preset("fixed-wing");  // 15 deg, clearance 30 m, acceptance 100 m
};

TEST_F(FitEarlyDescent, TheHeightPastARidgeIsHeldForTheAcceptanceRadius) {
  const std::vector<Vec3> straight = {at(2, 90), at(57, 40)};
  EnvelopeFitSpec spec;
  spec.envelope = fixed_wing;
  const EnvelopeFit fit = fit_to_envelope(straight, spec, t);
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path);
  ASSERT_EQ(c.envelope.size(), 8u);  // early-descent, then flown-clearance
  EXPECT_TRUE(every_limit_met(c));
  spec.envelope.acceptance_radius_m = 0;
  const EnvelopeFit reaching = fit_to_envelope(straight, spec, t);
  const PathCheck flown = judge(reaching.path);
  EXPECT_TRUE(flown.envelope[0].met);
  EXPECT_FALSE(flown.envelope[6].met) << "worst " << flown.envelope[6].worst;
}

// A leg no longer than the acceptance radius is flown at the lower of its
// two heights from the radius before its start (PX4 steps to its end
// height there): the fit holds such a leg's end over that ground too.
TEST_F(FitEarlyDescent, AShortLegsEndIsHeldOverTheGroundFromTheRadiusBeforeIt) {
  // an 80 m leg down 20 m, begun 70 m past the ridge
  const std::vector<Vec3> stepped = {at(2, 100), at(27, 100), at(35, 80), at(57, 80)};
  const PathCheck before = judge(stepped);
  ASSERT_FALSE(before.envelope[6].met);
  EXPECT_NEAR(before.envelope[6].worst, 20.0, 1e-6);
  EnvelopeFitSpec spec;
  spec.envelope = fixed_wing;
  const EnvelopeFit fit = fit_to_envelope(stepped, spec, t);
  EXPECT_TRUE(fit.feasible);
  const PathCheck c = judge(fit.path);
  EXPECT_TRUE(every_limit_met(c));
}

// An end whose last leg is held over the ridge (it is taken 100 m before
// the leg's start, 70 m past the ridge, and the end is the lower): every
// point clears the ridge 100 m behind it, but no fit moves the end, so the
// path is not inside the envelope, as the check says.
TEST_F(FitEarlyDescent, AnEndUnderItsLastLegsHeldStretchIsNotInsideTheEnvelope) {
  const std::vector<Vec3> to_low_end = {at(2, 100), at(27, 100), at(35, 80)};  // the last leg 80 m
  EnvelopeFitSpec spec;
  spec.envelope = fixed_wing;
  const EnvelopeFit fit = fit_to_envelope(to_low_end, spec, t);
  EXPECT_FALSE(fit.feasible);
  const PathCheck c = judge(fit.path);
  for (std::size_t k = 0; k < 6; ++k) EXPECT_TRUE(c.envelope[k].met) << c.envelope[k].name;
  EXPECT_FALSE(c.envelope[6].met);
  EXPECT_EQ(fit.path.back(), to_low_end.back());
}

// A vertex just before a low end, on a short leg held over the ridge: the
// end keeps it within a few metres of its own height, under the floor the
// ridge asks for, so the path is not inside the envelope.
TEST_F(FitEarlyDescent, AHeldFloorTheEndPutsOutOfReachIsNotInsideTheEnvelope) {
  const std::vector<Vec3> near_the_end = {at(2, 100), at(27, 100), at(34.6, 80), at(35, 80)};
  EnvelopeFitSpec spec;
  spec.envelope = fixed_wing;
  const EnvelopeFit fit = fit_to_envelope(near_the_end, spec, t);
  EXPECT_FALSE(fit.feasible);
  const PathCheck c = judge(fit.path);
  EXPECT_FALSE(c.envelope[6].met);
}

// An end the user put low just past the ridge: no path to it clears the
// ridge flown that way, and the check says so; the fit holds everything
// else and does not chase the floor the end puts out of reach.
TEST_F(FitEarlyDescent, AnEndLowJustPastARidgeIsLeftForTheCheckToReport) {
  const std::vector<Vec3> straight = {at(2, 90), at(24, 80)};
  EnvelopeFitSpec spec;
  spec.envelope = fixed_wing;
  const EnvelopeFit fit = fit_to_envelope(straight, spec, t);
  EXPECT_FALSE(fit.feasible);  // not inside the envelope: the console says so, as the check does
  EXPECT_EQ(fit.path.front(), straight.front());
  EXPECT_EQ(fit.path.back(), straight.back());
  EXPECT_LE(fit.path.size(), 8u);
  const PathCheck c = judge(fit.path);
  for (std::size_t k = 0; k < 6; ++k) EXPECT_TRUE(c.envelope[k].met) << c.envelope[k].name;
  EXPECT_FALSE(c.envelope[6].met);
  EXPECT_NEAR(c.envelope[6].worst, 80.0 - 60.0, 0.5);  // at the end itself
}

// A climb inside the limit that PX4 cannot follow with the wind behind it
// (path_check_test, ClimbInATailwind: 16.9 m over the slope's top at 25 m/s
// over the ground): the fit raises it where that flight comes under the
// clearance, and the fitted path meets every limit, flown in both winds.
TEST(FitFlights, AClimbATailwindFallsBehindIsRaisedUntilItIsFlownClear) {
  const testing::ClimbSlope slope;
  const fields::Heightfield& t = slope.terrain;
  const std::vector<Vec3>& climb = slope.path;
  EnvelopeFitSpec spec;
  spec.envelope = *vehicle_preset("fixed-wing");
  ASSERT_FALSE(every_limit_met(judge_on(t, spec.envelope, climb)));  // flown-clearance
  const EnvelopeFit fit = fit_to_envelope(climb, spec, t);
  EXPECT_TRUE(fit.feasible);
  EXPECT_TRUE(every_limit_met(judge_on(t, spec.envelope, fit.path)));
}

}  // namespace
}  // namespace visvol::rt
