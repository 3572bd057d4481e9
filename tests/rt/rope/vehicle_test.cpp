#include "rt/rope/vehicle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace visvol::rt {
namespace {

TEST(Vehicle, PresetsAreValidAndDiffer) {
  const auto fw = vehicle_preset("fixed-wing");
  const auto mr = vehicle_preset("multirotor");
  ASSERT_TRUE(fw.ok() && mr.ok());
  EXPECT_TRUE(validate(*fw).ok());
  EXPECT_TRUE(validate(*mr).ok());
  EXPECT_EQ(fw->type, VehicleType::fixed_wing);
  EXPECT_EQ(mr->type, VehicleType::multirotor);
  EXPECT_GT(fw->min_turn_radius_m, 0.0);
  EXPECT_EQ(mr->min_turn_radius_m, 0.0);
  // a fixed-wing's autopilot takes each waypoint 100 m early; a multirotor reaches it
  EXPECT_EQ(fw->acceptance_radius_m, 100.0);
  EXPECT_EQ(mr->acceptance_radius_m, 0.0);
  EXPECT_LT(fw->max_climb_deg, mr->max_climb_deg);
  EXPECT_FALSE(vehicle_preset("helicopter").ok());
}

TEST(Vehicle, BadValuesAreRefusedByKey) {
  auto refused = [](void (*change)(VehicleEnvelope&), const char* key) {
    VehicleEnvelope v;
    change(v);
    const Status s = validate(v);
    EXPECT_FALSE(s.ok()) << key;
    EXPECT_NE(s.message().find(key), std::string::npos) << s.message();
  };
  refused([](VehicleEnvelope& v) { v.max_climb_deg = 0; }, "max-climb");
  refused([](VehicleEnvelope& v) { v.max_climb_deg = std::nan(""); }, "max-climb");
  refused([](VehicleEnvelope& v) { v.max_descent_deg = 91; }, "max-descent");
  refused([](VehicleEnvelope& v) { v.min_turn_radius_m = -1; }, "min-turn-radius");
  refused([](VehicleEnvelope& v) { v.acceptance_radius_m = -1; }, "acceptance-radius");
  refused([](VehicleEnvelope& v) { v.acceptance_radius_m = std::nan(""); }, "acceptance-radius");
  refused([](VehicleEnvelope& v) { v.acceptance_radius_m = 1e300; }, "[0, 10000] m");
  refused([](VehicleEnvelope& v) { v.speed_m_per_s = 0; }, "speed");
  refused([](VehicleEnvelope& v) { v.speed_m_per_s = 4.9e-324; }, "speed");  // denormal: inf s of exposure
  refused([](VehicleEnvelope& v) { v.speed_m_per_s = 0.05; }, "[0.1, 1000] m/s");
  refused([](VehicleEnvelope& v) { v.clearance_m = std::nan(""); }, "clearance");
  refused([](VehicleEnvelope& v) { v.max_altitude_m = std::nan(""); }, "max-altitude");
  refused([](VehicleEnvelope& v) { v.max_altitude_m = -1e300; }, "max-altitude -1e+300 is not a height in");
  refused([](VehicleEnvelope& v) { v.max_altitude_m = -VehicleEnvelope::kNone; }, "max-altitude");
  refused([](VehicleEnvelope& v) { v.max_altitude_m = 1.5e5; }, "max-altitude");
  // contradictory: a ceiling under the clearance
  refused([](VehicleEnvelope& v) { v.max_agl_m = 20; }, "max-agl");
}

// How early a height may be flown: PX4's fixed-wing ramps its altitude to no
// nearer its waypoint than its loiter radius (80 m by default), whatever the
// mission's acceptance radius; ArduPlane to its radius; a multirotor, or a
// radius of 0, reaches each waypoint.
TEST(Vehicle, TheAltitudeHoldIsAtLeastPx4sLoiterRadius) {
  VehicleEnvelope v = *vehicle_preset("fixed-wing");
  v.max_wind_m_per_s = 0;
  EXPECT_EQ(altitude_hold_m(v), 100.0);
  v.acceptance_radius_m = 45;
  EXPECT_EQ(altitude_hold_m(v), kPx4LoiterRadiusM);
  v.autopilot = Autopilot::ardupilot;
  EXPECT_EQ(altitude_hold_m(v), 45.0);
  v.acceptance_radius_m = 0;
  v.autopilot = Autopilot::px4;
  EXPECT_EQ(altitude_hold_m(v), 0.0);
  VehicleEnvelope m = *vehicle_preset("multirotor");
  m.acceptance_radius_m = 45;
  EXPECT_EQ(altitude_hold_m(m), 45.0);
}

// A fixed-wing's autopilot switches waypoints farther out the faster it goes
// over the ground: with the strongest wind behind it, (speed + wind) / speed
// times the radius (PX4 at 20 m/s with 5 m/s of tailwind: 125 m), and holds
// its heights that far early. A multirotor's radius is a distance it reaches.
TEST(Vehicle, AFixedWingTakesItsWaypointsFartherOutInAWind) {
  VehicleEnvelope v = *vehicle_preset("fixed-wing");
  EXPECT_EQ(v.max_wind_m_per_s, kFixedWingPresetWindMPerS);  // 5 m/s
  EXPECT_DOUBLE_EQ(switch_distance_m(v), 125.0);
  v.max_wind_m_per_s = 0;
  EXPECT_EQ(switch_distance_m(v), 100.0);
  v.max_wind_m_per_s = 5;
  EXPECT_DOUBLE_EQ(altitude_hold_m(v), 125.0);
  v.acceptance_radius_m = 40;  // under PX4's loiter radius, even with the wind
  EXPECT_DOUBLE_EQ(switch_distance_m(v), 50.0);
  EXPECT_EQ(altitude_hold_m(v), kPx4LoiterRadiusM);
  v.autopilot = Autopilot::ardupilot;  // the mission's param 2, a distance
  EXPECT_DOUBLE_EQ(switch_distance_m(v), 40.0);
  EXPECT_DOUBLE_EQ(altitude_hold_m(v), 40.0);
  v.acceptance_radius_m = 0;
  EXPECT_EQ(switch_distance_m(v), 0.0);
  VehicleEnvelope m = *vehicle_preset("multirotor");
  m.acceptance_radius_m = 10;
  m.max_wind_m_per_s = 5;
  EXPECT_EQ(switch_distance_m(m), 10.0);
  for (double bad : {-1.0, 100.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    VehicleEnvelope w = *vehicle_preset("fixed-wing");
    w.max_wind_m_per_s = bad;
    const Status s = validate(w);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_NE(s.message().find("max-wind"), std::string::npos) << s.message();
  }
}

}  // namespace
}  // namespace visvol::rt
