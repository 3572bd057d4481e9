// The flight envelope a planned path must stay inside: what the vehicle can
// fly (climb, descent, turn) and where it may fly (clearance above the
// terrain, a ceiling above the terrain and above the datum).
//
// Angles in degrees from the horizontal, lengths in metres, speed in metres
// per second. A limit of +infinity means "none" (a multirotor turns on the
// spot: min_turn_radius_m 0). max_agl_m left infinite means "the field's top"
// to the planner, which bounds `show` there (F_p grows upward, so "most seen"
// is only well posed under a ceiling).
//
// Turn radius: the largest radius of the circular arcs an autopilot flies
// at the waypoints, tangent to both segments, without two arcs overlapping
// (rt::turn_radii_m in rt/rope/path_check.hpp).
//
// Values, no allocation beyond the name; thread-compatible.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "base/status.hpp"

namespace visvol::rt {

enum class VehicleType : std::uint8_t { fixed_wing = 0, multirotor = 1 };
const char* to_string(VehicleType type);  // "fixed-wing", "multirotor"

// The flight stack a mission is written for (a QGroundControl .plan's
// firmwareType): PX4 or ArduPilot.
enum class Autopilot : std::uint8_t { px4 = 0, ardupilot = 1 };
const char* to_string(Autopilot autopilot);  // "px4", "ardupilot"
// "px4" or "ardupilot"; false for anything else.
bool parse_autopilot(const std::string& text, Autopilot& out);

// The fixed-wing preset's wind: a mission planned for calm air had legs just
// over the hold distance ramped, and 1 m/s of tailwind had them stepped
// (stop 41: 30.5 m judged at 0 m/s, 10.8 m at 1 m/s); planned for 5 m/s, the
// same missions cost 0 to 1% more F_c.
inline constexpr double kFixedWingPresetWindMPerS = 5.0;

struct VehicleEnvelope {
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  // A max-altitude, when there is one, lies within this of the datum, m.
  static constexpr double kMaxAltitudeRangeM = 1.0e5;

  std::string name = "fixed-wing";  // preset or file it came from
  VehicleType type = VehicleType::fixed_wing;
  double speed_m_per_s = 20.0;      // cruise speed, m/s: over the ground in still air (exposure time, .plan speeds)
  double max_climb_deg = 15.0;      // steepest climb of a segment
  double max_descent_deg = 15.0;    // steepest descent of a segment (positive)
  double min_turn_radius_m = 80.0;  // tightest fillet at a waypoint, 0 for none
  double clearance_m = 30.0;        // least height above the finest terrain
  double max_agl_m = kNone;         // highest height above the finest terrain
  double max_altitude_m = kNone;    // highest height above the datum
  // How far before a waypoint the autopilot takes the next one, and with it
  // the next altitude: a fixed-wing's PX4 switches at its L1 distance (about
  // 95 m at 20 m/s), ArduPlane within WP_RADIUS (90 m); at cruise speed (a
  // PX4 fixed-wing's grows with the wind: switch_distance_m). The path must
  // then clear the highest ground that far behind each point, and a leg no
  // longer than the hold, at its lower height, the ground from that far
  // before its start (rt::TrackGround). 0: the vehicle reaches each waypoint.
  double acceptance_radius_m = 100.0;
  // The strongest wind the mission is flown in, m/s. A PX4 fixed-wing
  // switches waypoints farther out the faster it goes over the ground (its
  // L1 distance is 4.8 s of flight): a tailwind takes the heights earlier
  // than the radius says (switch_distance_m). The fixed-wing preset's.
  double max_wind_m_per_s = kFixedWingPresetWindMPerS;
  Autopilot autopilot = Autopilot::px4;
};

// PX4's fixed-wing controller ramps a leg's altitude (its first-order hold)
// to the larger of its switch distance and the waypoint's loiter radius
// before the waypoint, and on a leg no longer than that steps to the
// waypoint's altitude instead; a plain mission waypoint's loiter radius is
// NAV_LOITER_RAD, 80 m by default.
inline constexpr double kPx4LoiterRadiusM = 80.0;

// PX4's navigator takes a fixed-wing's waypoint only within this of its
// height, m (NAV_FW_ALT_RAD, 10 m by default).
inline constexpr double kPx4AltitudeAcceptanceM = 10.0;

// A PX4 fixed-wing's flights are flown at ground speeds from calm air to the
// strongest tailwind this far apart, m/s (up to 20 m/s of wind: at most
// kMaxPx4Flights flights, rt::px4_flights): the least clearance is not
// always at either end of the range (a SF North mission flown by an
// independent simulation: 30.57 m at 20 m/s and 30.28 m at 25, 29.92 m at
// 22.5). A sampling: nothing is flown between.
inline constexpr double kPx4GroundSpeedStepMPerS = 0.5;

// A fixed-wing flown by PX4: its switch distance grows with the wind, and it
// holds its heights at least its loiter radius early.
inline bool is_px4_fixed_wing(const VehicleEnvelope& e) {
  return e.type == VehicleType::fixed_wing && e.autopilot == Autopilot::px4;
}

// How far before a waypoint the vehicle takes the next one, m: the
// acceptance radius, for a PX4 fixed-wing grown with its ground speed in the
// strongest wind, (speed + max wind) / speed times (the radius is the
// switch distance at cruise speed: PX4's L1 and NPFG switch distances grow
// with ground speed; where the mission's param 2 is the larger, PX4 keeps
// it, and this is conservative). ArduPlane switches at the mission's param
// 2, a distance whatever the wind (visvol writes it). An independent
// simulation of PX4 1.13's L1 guidance flew a mission planned for 100 m at
// 22 m/s over the ground, switching at 105 m: legs of 104 m planned as ramps
// were stepped and flown 22 m under the plan (stop 41).
double switch_distance_m(const VehicleEnvelope& e);

// How far before a waypoint the vehicle may already fly at its height, m
// (rt::TrackGround): the switch distance, and for a PX4 fixed-wing with
// one, at least kPx4LoiterRadiusM. 0 where the vehicle reaches each waypoint.
double altitude_hold_m(const VehicleEnvelope& e);

// The presets: "fixed-wing" (20 m/s, climb and descent 15 deg, turns of 80 m
// or wider, a 100 m acceptance radius at cruise speed, 125 m in its 5 m/s of
// wind) and "multirotor" (8 m/s, climb 60
// deg, descent 45 deg, no turn limit, each waypoint reached). Errc::invalid_argument naming the value otherwise.
Result<VehicleEnvelope> vehicle_preset(const std::string& name);

// Checks every value (finite where it must be, in range, consistent: a
// ceiling above the clearance). Errors name the key as the user spells it
// ("max-climb", "max-agl", ...) and the value.
Status validate(const VehicleEnvelope& envelope);

}  // namespace visvol::rt
