// The independent assessment of a path (the paper's path assessment, and the
// check a crew trusts): every constraint and envelope limit measured on the
// finest terrain, never on the field or the planner's own numbers.
//
// - Hidden from / visible to a point: Franklin & Ray's R3 sight line
//   (fields::r3_visible) from the observer's eye to samples along the path,
//   at most `sample_step_m` apart (default a sixteenth of the post spacing), each
//   sample standing for its share of the path's length.
// - Clearance, height above the terrain (AGL) and altitude: at the same
//   samples, against the bilinear finest terrain, for their share of the
//   length; and the lowest and highest point above that terrain along each
//   segment exactly (at every grid line crossed and the extreme between,
//   where the bilinear terrain is a quadratic along the segment), so a peak
//   between samples is never missed.
// - Early descent (a vehicle with an acceptance radius; R below is its
//   switch distance in the strongest wind, rt::switch_distance_m, and its
//   hold rt::altitude_hold_m; rt/rope/track_ground.hpp):
//   the clearance at the same samples over the highest terrain under the R
//   metres of track behind each (and one sample step more), for their share
//   of the length: the height an autopilot that takes each waypoint's
//   height R early flies over the ground. On a segment no longer than R
//   (PX4 steps to the next height there, from R before the segment's
//   start), no more than the lower of its two heights over the highest
//   terrain of its held stretch, exactly. Along the segments, not the arcs.
// - Climb and descent: every segment's angle from the horizontal.
// - Turn radius: the largest flyable fillet at every interior vertex
//   (turn_radii_m below), weighted by half of each neighbouring segment.
// - The arc a fixed-wing flies by each corner on (inside it, tangent to both
//   segments, at the envelope's min_turn_radius_m or the smaller radius the
//   segments leave room for, turn_radii_m's; a run of vertices on one spot
//   is one corner: rt/rope/fillet.hpp): its samples judge the constraints,
//   clearance, max-agl, max-altitude and the bounds (clearance and max-agl
//   exactly along its chords), at no share of the length, so a failure only
//   there reads "holds on 0.999 of the length", NOT MET. Climb and turn
//   are judged on the segments and vertices only.
// - Flown clearance (a PX4 fixed-wing with an acceptance radius; not where
//   the caller gives turn radii, a loiter's circle): the track its L1
//   guidance flies (rt/rope/l1_track.hpp), which cuts a corner deeper than
//   the arc and several at once where the legs are shorter than the switch
//   distance, in still air, with the strongest wind behind it and at
//   ground speeds 0.5 m/s apart between (rt::px4_flights), sampled as the
//   path is (or a controller step apart, the longer: 0.4 m at 20 m/s), at
//   the height flown (PX4 1.13's first-order hold of each leg's heights,
//   followed at the airframe's climb and sink rates: rt::fly_l1), for their
//   share of the flown length: "flown-clearance". Unmet where a flight
//   does not reach the end in time (three times what its legs and their
//   climbs take, and two minutes more, at most a day: rt::fly_l1).
// - Planning bounds: the samples inside the trusted region.
// A requirement is met when every sample, segment or vertex satisfies it
// (satisfied_fraction == 1).
//
// Offline: allocates (a copy of the finest terrain at construction).
// Thread-compatible: check() is const and may run on several threads.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "base/tolerances.hpp"
#include "fields/heightfield.hpp"
#include "fields/volume.hpp"
#include "rt/rope/l1_track.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/vehicle.hpp"

namespace visvol::rt {

enum class ConstraintKind : std::uint8_t { hidden_from = 0, visible_to = 1 };
const char* to_string(ConstraintKind kind);  // "hidden-from", "visible-to"

// The highest an observer may stand or fly, metres above the datum: higher is
// a mistyped number (a point 1e300 m up was accepted, and seen by no path).
inline constexpr double kMaxObserverAltitudeM = 1.0e5;
// Positions against the planning bounds: visvol::kBoundsTolM (base/tolerances.hpp).
// The default sample step, in posts: the sight lines to the constraint
// points are exact at each sample, and a stretch seen (or hidden) between
// two samples is missed. A quarter post missed 13 m in sight between samples
// about 20 m apart on a 90 m grid (a skeptic's plan, reported met); a sixteenth
// (5.6 m there, 1.9 m at 30 m) costs four times the sight lines.
inline constexpr double kSightStepPosts = 1.0 / 16;
// "NAME: Z 1e+300 m is above the 100000 m an observer may be" where `z_m` is
// over kMaxObserverAltitudeM (the options, the console, the hull maker).
Status check_observer_altitude(const std::string& name, double z_m);

// An observer as a user names it: a point at or above the finest terrain
// (pack CRS metres), whose eye is `eye_height_m` above it.
struct ConstraintPoint {
  ConstraintKind kind = ConstraintKind::hidden_from;
  Vec3 point_m = Vec3::Zero();
  double eye_height_m = 2.0;
  Vec3 eye_m() const { return point_m + Vec3(0, 0, eye_height_m); }
};

struct PathCheckSpec {
  VehicleEnvelope envelope;  // limits; max_agl_m infinite: none
  std::vector<ConstraintPoint> constraints;
  std::optional<fields::Bounds2D> planning_bounds;
  double curvature_coeff = 0;  // the pack's Earth curvature and refraction
  double sample_step_m = 0;    // 0: kSightStepPosts of the terrain's post spacing
};

// A satisfied fraction as reports print it (3 decimals), rounded down: a
// requirement held on 0.9996 of the length reads 0.999, never the 1.000 of
// one that is met.
inline double fraction_shown(double fraction) {
  if (fraction >= 1) return 1;
  return std::min(std::floor(fraction * 1000.0 + 1e-9) / 1000.0, 0.999);
}

struct ConstraintResult {
  ConstraintPoint constraint;
  double satisfied_fraction = 0;  // of the path's length
  double seen_m = 0;              // length of path in sight of the observer
  bool met = false;
};

// The name of the clearance along a PX4 fixed-wing's flights (a share of
// the flown length, not of the path's).
inline constexpr const char* kFlownClearance = "flown-clearance";

struct LimitResult {
  // "clearance", "max-agl", "max-altitude", "max-climb", "max-descent", "min-turn-radius",
  // "early-descent" (for a vehicle with an acceptance radius) and
  // "flown-clearance" (last, for a PX4 fixed-wing with one)
  std::string name;
  std::string unit;               // "m", "deg"
  double limit = 0;               // as asked
  double worst = 0;               // the path's worst value (lowest for a lower limit, highest for an upper)
  double satisfied_fraction = 1;  // of the path's length
  bool met = true;
  bool lower = false;  // a lower limit (clearance, min-turn-radius): the worst is the lowest
};

// Decimals to print an unmet limit and its worst value with (1 to 7): enough
// that the worst reads past the limit ("clearance 30.00 m: worst 29.96 m",
// never "worst 30.0 m ... NOT MET"; the tolerances are 1 cm and 1e-6). 1 for
// a met limit.
inline constexpr int kMaxWorstDecimals = 7;
int worst_decimals(const LimitResult& l);

struct VertexCheck {
  double fp = 0;             // F_p of the field at the vertex (informative)
  double ground_m = 0;       // finest terrain below it
  double clearance_m = 0;    // height above it
  double climb_deg = 0;      // of the segment to the next vertex (negative: descent; a fixed-wing's
                             // arc by a corner may climb more steeply, and max-climb's worst counts it)
  double turn_radius_m = 0;  // the largest flyable turn radius here (turn_radii_m; infinite: straight or an end)
  // the lowest height over the ground flown early on the segment to the next
  // vertex (early-descent's; infinite without an acceptance radius and at
  // the last vertex)
  double early_m = std::numeric_limits<double>::infinity();
  std::vector<bool> seen_by;  // per constraint: the observer sees this vertex (R3)
};

struct PathCheck {
  double fc = 0;  // F_c of the field along the path
  double length_m = 0;
  double duration_s = 0;  // at the vehicle's speed
  std::vector<ConstraintResult> constraints;
  std::vector<LimitResult> envelope;
  double inside_bounds_fraction = 1;  // of the path's length inside the planning bounds
  bool inside_planning_bounds = true;
  std::vector<VertexCheck> per_vertex;
  bool all_met = false;  // every constraint and limit, and inside the bounds
  // Sum over requirements of the unmet fraction, at least kMinUnmetShare
  // each (0 when all are met): a ranking of infeasible paths, least
  // violation first.
  static constexpr double kMinUnmetShare = 1e-6;
  // Two violations closer than this rank alike (a thousandth of the least one).
  static constexpr double kViolationTie = 1e-9;
  double violation = 0;
  // The part of `violation` that the vehicle's envelope and the planning
  // bounds make (clearance, ceilings, climb, descent, turns): what makes a
  // path unsafe or unflyable, as the constraint points do not.
  double flight_violation = 0;

  // "hidden-from (x, y, z): 0.82 of the length" lines for what is unmet.
  std::vector<std::string> unmet() const;
};

// How a PX4 fixed-wing flies the path laterally (rt/rope/l1_track.hpp: its
// L1 guidance, switching early and cutting towards the next leg), at one
// speed over the ground (rt::PathChecker::fly): its clearance is the
// "flown-clearance" requirement; the rest is a report.
struct FlownCheck {
  double ground_speed_m_per_s = 0;
  double switch_distance_m = 0;  // the next waypoint taken within this (the radius or the L1 distance)
  double altitude_hold_m = 0;    // a leg's end height reached this far before it (rt::L1Flight)
  double length_m = 0;           // of the flown track
  // The least height over the finest terrain along the flown track, at the
  // height flown (rt::fly_l1), and where.
  double least_clearance_m = std::numeric_limits<double>::infinity();
  Vec3 least_at_m = Vec3::Zero();
  double clearance_fraction = 1;  // of the flown length at or above the clearance
  // the farthest the track goes from the legs about the one it flies (two
  // either way), horizontally
  double max_off_path_m = 0;
  std::vector<double> constraint_fractions;  // per constraint: of the flown length that satisfies it
  bool reached_end = false;
  // PathChecker::fly: the flight it reports as the lowest of all it flew
  // (one that stops short first, then the least clearance)
  bool lowest = false;
  int flights_flown = 0;  // PathChecker::fly: how many flights it flew (rt::px4_flights)
};

// The flights the "flown-clearance" requirement flies, and
// rt::fit_to_envelope fits the heights to: a PX4 fixed-wing with an
// acceptance radius in still air at its cruise speed, with the strongest
// wind behind it (cruise plus wind over the ground), and at ground speeds
// between them kPx4GroundSpeedStepMPerS apart (at most kMaxPx4Flights in
// all: farther apart over 20 m/s of wind), each as PX4 1.13 flies
// at that ground speed: waypoints taken at the radius or the L1 distance,
// heights held the L1 distance or NAV_LOITER_RAD early, the larger, climb
// and sink at the envelope's angles at cruise airspeed, a waypoint taken
// only within NAV_FW_ALT_RAD of its height (rt::L1Flight). None for another
// vehicle.
inline constexpr int kMaxPx4Flights = 41;
std::vector<L1Flight> px4_flights(const VehicleEnvelope& envelope);

class PathChecker {
 public:
  // `terrain` is the finest level's terrain; `field` gives F_p (may be null:
  // fp and fc are then 0). Refuses a constraint point outside the terrain or
  // below it, naming the point's option ("--hidden-from").
  static Result<PathChecker> create(fields::Heightfield terrain, const PathField* field, PathCheckSpec spec);

  // Samples a whole check takes at most, times its observers (each sample
  // draws a sight line to each): about ten seconds of work.
  static constexpr double kMaxSamples = 1e7;
  // Samples a segment takes at most: a longer one is sampled more sparsely.
  // Above kMaxSamples, so a path that callers let through sample_count()
  // is never thinned (a bound for the conversion, not for the work).
  static constexpr int kMaxSegmentSamples = 1 << 24;
  static_assert(kMaxSegmentSamples > kMaxSamples, "a path callers accept is sampled as promised");

  PathCheck check(const Vec3* vertices, int count) const { return check(vertices, count, nullptr); }
  // With the turn radius the autopilot flies at each vertex where the caller
  // knows it (a loiter's circle; NaN elsewhere, and a null array: the
  // path's geometry decides, turn_radii_m).
  PathCheck check(const Vec3* vertices, int count, const double* turn_radius_m) const;
  PathCheck check(const std::vector<Vec3>& path) const { return check(path.data(), static_cast<int>(path.size())); }
  // The samples a check of the path takes (infinite for a vertex that is
  // not finite), less a PX4 fixed-wing's flights (their clearance alone, no
  // sight line: about a ground height a sample): compare with kMaxSamples
  // before checking outside input.
  double sample_count(const std::vector<Vec3>& path) const;
  // A PX4 fixed-wing's flights of the path (FlownCheck, rt::px4_flights)
  // for a report: the one in still air, the one with the strongest
  // tailwind, and the lowest where that is neither (FlownCheck::lowest), in
  // order of ground speed; sampled as check() samples, each sample's sight
  // line to every constraint point. None for another vehicle, one that
  // reaches each waypoint, or a path with a vertex that is not finite. Costs
  // every flight's clearance and about as much as check() per flight
  // reported.
  std::vector<FlownCheck> fly(const std::vector<Vec3>& path) const;

  const PathCheckSpec& spec() const { return spec_; }
  const fields::Heightfield& terrain() const { return terrain_; }
  // Bilinear finest terrain at a world point (clamped to the grid).
  double ground_m(double x, double y) const;
  // The observer of constraint c sees world point p (R3 on the finest terrain).
  bool sees(const ConstraintPoint& c, const Vec3& p) const;

 private:
  PathChecker() = default;
  fields::Heightfield terrain_;
  const PathField* field_ = nullptr;
  PathCheckSpec spec_;
};

// Does path a (its check) meet less than path b: not every requirement where
// b meets them all, or more violation of the envelope and the bounds, or (as
// much of those) more of the constraint points? (F_c aside.)
bool meets_less(const PathCheck& a, const PathCheck& b);

}  // namespace visvol::rt
