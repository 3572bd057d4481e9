// The ground track a PX4 fixed-wing flies along a path's legs: PX4 1.13's
// L1 guidance (ECL_L1_Pos_Controller::navigate_waypoints: fly to the leg's
// start while far behind it, back to its end once past it, else track the
// line through both with the L1 point at most 45 degrees off; lateral
// acceleration 4 damping^2 V^2 / L1 sin(eta), eta within 90 degrees, bank
// within the roll limit) at a constant speed over the ground, taking the
// next waypoint within its switch distance (or its L1 distance, the larger),
// one a step, as the navigator does (with a hold, only within its altitude
// gate, NAV_FW_ALT_RAD; not modelled: a wind's drift in the turns: a
// tailwind is flown as a faster ground speed). The arc by a corner (rt/rope/fillet.hpp)
// is the track of a vehicle that turns at its radius; this is where an
// autopilot that switches early and cuts towards the next leg flies: deeper
// inside the corner, and across several corners where the legs are shorter
// than the switch distance.
//
// Heights: with a hold (altitude_hold_m > 0), PX4 1.13's first-order hold
// (FixedwingPositionControl::control_auto_position): the height setpoint
// ramps from the leg's start height to its end height, reached the hold
// distance before the end (measured by the least distance to the end so
// far); on a leg no longer than the hold it is the end height at once. The
// aircraft follows the setpoint at no more than its climb and sink rates, so
// a steep climb at a fast ground speed falls behind the plan (no lag of
// the altitude controller is modelled: the clearance is the margin for it).
// Without a hold: the planned height at the nearest point of the leg flown.
//
// Offline: allocates the track. Thread-compatible.
#pragma once

#include <limits>
#include <vector>

#include "rt/rope/rope.hpp"

namespace visvol::rt {

struct L1Flight {
  double ground_speed_m_per_s = 20.0;
  double switch_distance_m = 100.0;  // the next waypoint is taken within this (horizontal)
  double period_s = 20.0;            // PX4's FW_L1_PERIOD default
  double damping = 0.75;             // FW_L1_DAMPING default
  double max_roll_deg = 50.0;        // FW_R_LIM default
  double step_s = 0.02;              // the controller's rate, 50 Hz
  // A point is kept where the aircraft has flown this far from the last
  // kept (0: every step; the check keeps its sample step): the track's
  // memory is its length over this, not its duration.
  double record_every_m = 0.0;
  // How far before a leg's end its height is reached, m (PX4: the L1
  // distance at this ground speed or the loiter radius NAV_LOITER_RAD, the
  // larger); 0: no hold. Climb and sink rates, m/s, with a hold.
  double altitude_hold_m = 0.0;
  double max_climb_m_per_s = std::numeric_limits<double>::infinity();
  double max_sink_m_per_s = std::numeric_limits<double>::infinity();
  // With a hold, a waypoint is taken only within this of its height, m
  // (PX4's NAV_FW_ALT_RAD): until then the aircraft flies on to it, and past
  // it L1 guidance turns it back (PX4's loiter there is not modelled).
  double altitude_gate_m = std::numeric_limits<double>::infinity();
  // L1 distance, m: damping period V / pi (95.5 m at 20 m/s)
  double l1_distance_m() const;
  // Where the next waypoint is taken, m: the switch distance or the L1
  // distance, the larger (PX4's navigator)
  double accept_distance_m() const;
};

struct FlownPoint {
  Vec3 p_m = Vec3::Zero();
  int leg = 0;  // flying from waypoint `leg` to `leg + 1`
};

// The steps a flight takes at most (a day of flight at 50 Hz): a slow
// vehicle on a long path stops there, short of the end.
inline constexpr double kMaxL1Steps = 4.32e6;

struct FlownTrack {
  // from the first waypoint, a step (or L1Flight::record_every_m) apart,
  // and the last position flown
  std::vector<FlownPoint> points;
  // the last waypoint taken in time (within the switch distance, and with a
  // hold within the altitude gate of its height)
  bool reached_end = false;
};

// PX4 1.13's sin(eta) on a leg's line: eta = asin(sin_eta1) + atan2(cross_v,
// dot_v) clamped to 90 degrees either way (sin_eta1 within +-0.7071, the
// cross-track angle's sine; cross_v and dot_v the velocity across and along
// the leg), computed without trigonometric calls.
double l1_sin_eta(double sin_eta1, double cross_v, double dot_v);

// The fraction (0 to 1) along leg a-b of its point nearest (x, y),
// horizontally (0 for a leg on one spot).
double leg_fraction(const Vec3& a, const Vec3& b, double x, double y);

// Flies `path` from its first waypoint, heading for the first waypoint off
// its spot (none 1 cm away horizontally: nothing is flown), until it takes
// the last one (within the switch distance, and with a hold within the
// altitude gate of its height), or for three times the time its length takes
// at the speed (with a hold, and its climbs and descents at the rates) and
// two minutes more, or kMaxL1Steps (not reached_end).
FlownTrack fly_l1(const std::vector<Vec3>& path, const L1Flight& flight);

}  // namespace visvol::rt
