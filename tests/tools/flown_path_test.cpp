#include "flown_path.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "base/angles.hpp"

namespace visvol::cli {
namespace {

rt::VehicleEnvelope fixed_wing() { return *rt::vehicle_preset("fixed-wing"); }

// A straight mission west to east through a loiter at the origin.
PathFile through_loiter(const LoiterItem& l) {
  PathFile f;
  f.points = {{-500, 0, 100}, {0, 0, l.altitude_m}, {500, 0, 100}};
  f.has_heights = true;
  f.format = PathFormat::qgc_plan;
  LoiterItem own = l;
  own.vertex = 1;
  own.item = "mission.items[2]";
  f.loiters = {own};
  return f;
}

LoiterItem loiter(LoiterKind kind, double radius_m, double amount = 0, double altitude_m = 100) {
  LoiterItem l;
  l.kind = kind;
  l.radius_m = radius_m;
  l.amount = amount;
  l.altitude_m = altitude_m;
  return l;
}

double degrees_from_horizontal(const Vec3& a, const Vec3& b) {
  return std::atan2(b.z() - a.z(), std::hypot(b.x() - a.x(), b.y() - a.y())) * 180.0 / kPi;
}

// The aircraft joins the circle along the tangent from where it comes,
// circles at the radius in the sense the sign gives, and leaves along the
// tangent to where it goes; the centre itself is not flown.
TEST(FlownPath, ALoiterIsACircleJoinedAndLeftAlongTangents) {
  for (double radius : {100.0, -100.0}) {
    Result<FlownPath> f = fly_path(through_loiter(loiter(LoiterKind::unlimited, radius)), fixed_wing());
    ASSERT_TRUE(f.ok()) << f.status().message();
    const std::vector<Vec3>& p = f->points;
    ASSERT_EQ(p.size(), f->turn_radius_m.size());
    ASSERT_GE(p.size(), 38u);  // one turn of 36 chords and more
    EXPECT_EQ(p.front(), Vec3(-500, 0, 100));
    EXPECT_EQ(p.back(), Vec3(500, 0, 100));
    EXPECT_TRUE(std::isnan(f->turn_radius_m.front()) && std::isnan(f->turn_radius_m.back()));
    // joined and left along tangents: the geometry judges those two points
    EXPECT_TRUE(std::isnan(f->turn_radius_m[1]) && std::isnan(f->turn_radius_m[p.size() - 2]));
    double swept = 0;
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      EXPECT_NEAR(std::hypot(p[k].x(), p[k].y()), 100.0, 1e-9) << k;
      if (k > 1 && k + 2 < p.size()) {
        EXPECT_EQ(f->turn_radius_m[k], 100.0);
      }
      EXPECT_EQ(f->vertex_of[k], -1);
      if (k + 2 < p.size()) {
        swept += std::atan2(p[k].x() * p[k + 1].y() - p[k].y() * p[k + 1].x(),
                            p[k].x() * p[k + 1].x() + p[k].y() * p[k + 1].y());
      }
    }
    // clockwise for a positive radius: the angle swept is negative
    EXPECT_GT(std::fabs(swept), 2 * kPi - 1e-6);
    EXPECT_EQ(swept<0, radius> 0);
    // tangents: the legs in and out are perpendicular to the radius where they touch
    const Vec3 in = p[1] - p[0], out = p[p.size() - 1] - p[p.size() - 2];
    EXPECT_NEAR(in.x() * p[1].x() + in.y() * p[1].y(), 0.0, 1e-6);
    const Vec3& leave = p[p.size() - 2];
    EXPECT_NEAR(out.x() * leave.x() + out.y() * leave.y(), 0.0, 1e-6);
    // ... the tangents whose direction is the circle's sense of flight
    auto along_circle = [&](const Vec3& q) {  // clockwise for a positive radius
      return radius > 0 ? Vec3(q.y(), -q.x(), 0) : Vec3(-q.y(), q.x(), 0);
    };
    EXPECT_GT(in.dot(along_circle(p[1])), 0.0);
    EXPECT_GT(out.dot(along_circle(leave)), 0.0);
    EXPECT_EQ(f->vertex_of.front(), 0);
    EXPECT_EQ(f->vertex_of.back(), 2);
    ASSERT_EQ(f->loiters.size(), 1u);
    EXPECT_NE(f->loiters[0].find("mission.items[2]: 1.0 turns of 100 m"), std::string::npos) << f->loiters[0];
  }
}

// Turns, seconds and the autopilot's own radius.
TEST(FlownPath, TurnsTimeAndDefaultRadius) {
  Result<FlownPath> turns = fly_path(through_loiter(loiter(LoiterKind::turns, 100, 3)), fixed_wing());
  ASSERT_TRUE(turns.ok());
  EXPECT_GE(turns->points.size(), 3u * 36u + 2u);
  EXPECT_NE(turns->loiters[0].find("3.0 turns"), std::string::npos) << turns->loiters[0];
  // 60 s at 20 m/s on a circle of 100 m: 1200 m, 1.9 turns
  Result<FlownPath> time = fly_path(through_loiter(loiter(LoiterKind::time, 100, 60)), fixed_wing());
  ASSERT_TRUE(time.ok());
  EXPECT_NE(time->loiters[0].find("1.9 turns"), std::string::npos) << time->loiters[0];
  // radius 0: the vehicle's min-turn-radius (80 m for the fixed-wing preset)
  Result<FlownPath> own = fly_path(through_loiter(loiter(LoiterKind::unlimited, 0)), fixed_wing());
  ASSERT_TRUE(own.ok());
  EXPECT_NEAR(std::hypot(own->points[1].x(), own->points[1].y()), 80.0, 1e-9);
  // a loiter longer than a check flies is refused by its item
  Result<FlownPath> long_time = fly_path(through_loiter(loiter(LoiterKind::time, 30, 1e6)), fixed_wing());
  ASSERT_FALSE(long_time.ok());
  EXPECT_NE(long_time.status().message().find("mission.items[2]:"), std::string::npos);
}

// LOITER_TO_ALT and any loiter at another altitude: the vehicle climbs at
// its steepest climb from the leg in on, never steeper, to the loiter's
// altitude; LOITER_TO_ALT circles as long as that takes.
TEST(FlownPath, AltitudeChangesAtTheSteepestClimbTheVehicleFlies) {
  const rt::VehicleEnvelope e = fixed_wing();
  for (LoiterKind kind : {LoiterKind::to_altitude, LoiterKind::turns}) {
    Result<FlownPath> f = fly_path(through_loiter(loiter(kind, 100, 3, 600)), e);
    ASSERT_TRUE(f.ok());
    const std::vector<Vec3>& p = f->points;
    double top = 0;
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      EXPECT_LE(degrees_from_horizontal(p[k - 1], p[k]), e.max_climb_deg) << k;
      top = std::max(top, p[k].z());
    }
    EXPECT_NEAR(top, 600.0, 1e-6);
    EXPECT_NEAR(p[p.size() - 2].z(), 600.0, 1e-6);  // it leaves at the loiter's altitude
  }
  Result<FlownPath> spiral = fly_path(through_loiter(loiter(LoiterKind::to_altitude, 100, 0, 600)), e);
  ASSERT_TRUE(spiral.ok());
  // 500 m at 15 degrees: 1866 m, 457 m of it on the leg in, the rest 2.2 turns
  EXPECT_NE(spiral->loiters[0].find("2.2 turns"), std::string::npos) << spiral->loiters[0];
  // any loiter reaches its altitude before it leaves, however short it is
  // asked to be: one 5 m up from a plain at 0, below the legs at 100 m
  for (LoiterKind kind : {LoiterKind::time, LoiterKind::turns, LoiterKind::unlimited}) {
    Result<FlownPath> low = fly_path(through_loiter(loiter(kind, 100, 0, 5)), e);
    ASSERT_TRUE(low.ok());
    double lowest = 1e9;
    for (const Vec3& q : low->points) lowest = std::min(lowest, q.z());
    EXPECT_NEAR(lowest, 5.0, 1e-6);
  }
}

// A loiter over the waypoint before it: the aircraft flies over the
// waypoint, then out to the circle straight ahead (from inside, the join
// is at the loiter's radius); a multirotor hovers on the spot instead.
TEST(FlownPath, OverAWaypointAndHovering) {
  PathFile f;
  f.points = {{-500, 0, 100}, {0, 0, 100}, {0, 500, 100}};
  LoiterItem l = loiter(LoiterKind::unlimited, 100, 0, 120);
  l.vertex = 1;
  l.over_waypoint = true;
  l.item = "mission.items[3]";
  f.loiters = {l};
  Result<FlownPath> fw = fly_path(f, fixed_wing());
  ASSERT_TRUE(fw.ok());
  ASSERT_GE(fw->points.size(), 5u);
  EXPECT_EQ(fw->points[1], Vec3(0, 0, 100));    // the waypoint itself
  EXPECT_NEAR(fw->points[2].x(), 100.0, 1e-9);  // straight ahead, east
  EXPECT_NEAR(fw->points[2].y(), 0.0, 1e-9);
  EXPECT_EQ(fw->turn_radius_m[2], 100.0);  // joined from inside: at the radius
  Result<FlownPath> mr = fly_path(f, *rt::vehicle_preset("multirotor"));
  ASSERT_TRUE(mr.ok());
  ASSERT_EQ(mr->points.size(), 4u);
  EXPECT_EQ(mr->points[2], Vec3(0, 0, 120));  // climbs on the spot
  EXPECT_NE(mr->loiters[0].find("hovers at 120.0 m"), std::string::npos) << mr->loiters[0];
  for (double held : mr->hold_s) EXPECT_EQ(held, 0.0);  // an unlimited loiter: no time counted
  // LOITER_TIME: it hovers its seconds there, which the length at the
  // speed does not count (a skeptic's 600 s hover was missing from the
  // mission's duration and exposure)
  PathFile timed = f;
  timed.loiters[0].kind = LoiterKind::time;
  timed.loiters[0].amount = 600;
  Result<FlownPath> waits = fly_path(timed, *rt::vehicle_preset("multirotor"));
  ASSERT_TRUE(waits.ok());
  ASSERT_EQ(waits->hold_s.size(), waits->points.size());
  EXPECT_EQ(waits->hold_s[2], 600.0);
  EXPECT_NE(waits->loiters[0].find("hovers at 120.0 m for 600.0 s"), std::string::npos) << waits->loiters[0];
  // a circle too small to draw turns on the spot at its radius; so does a
  // fixed-wing of no turn limit asked for the autopilot's radius
  f.loiters[0].radius_m = 0.005;
  Result<FlownPath> tiny = fly_path(f, fixed_wing());
  ASSERT_TRUE(tiny.ok());
  ASSERT_EQ(tiny->points.size(), 4u);
  EXPECT_EQ(tiny->turn_radius_m[2], 0.005);
  EXPECT_NE(tiny->loiters[0].find("turns on the spot"), std::string::npos) << tiny->loiters[0];
  // two loiters over one point in opposite senses: the reversal where the
  // second begins is judged by the geometry (a hairpin), not at a radius
  f.loiters = {l, l};
  f.loiters[1].radius_m = -100;
  Result<FlownPath> reverse = fly_path(f, fixed_wing());
  ASSERT_TRUE(reverse.ok());
  // the second begins where the first left its circle: both points there
  int reversals = 0;
  for (std::size_t k = 2; k + 1 < reverse->points.size(); ++k) {
    if ((reverse->points[k] - reverse->points[k + 1]).norm() > 1e-9) continue;
    ++reversals;
    EXPECT_TRUE(std::isnan(reverse->turn_radius_m[k]) && std::isnan(reverse->turn_radius_m[k + 1])) << k;
  }
  EXPECT_EQ(reversals, 1);
  // all loiters together fly a bounded number of points
  f.loiters.assign(40, loiter(LoiterKind::turns, 100, 1000, 100));
  for (LoiterItem& many : f.loiters) {
    many.vertex = 1;
    many.over_waypoint = true;
    many.item = "mission.items[9]";
  }
  Result<FlownPath> too_many = fly_path(f, fixed_wing());
  ASSERT_FALSE(too_many.ok());
  EXPECT_NE(too_many.status().message().find("more than"), std::string::npos) << too_many.status().message();
  // no loiters: the file's points as they are
  PathFile plain;
  plain.points = {{0, 0, 10}, {100, 0, 10}};
  Result<FlownPath> same = fly_path(plain, fixed_wing());
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->points, plain.points);
  EXPECT_TRUE(same->loiters.empty());
}

}  // namespace
}  // namespace visvol::cli
