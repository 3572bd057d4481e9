// How `visvol plan` and `visvol check` report a path's assessment
// (rt::PathCheck): the JSON members and the text lines they share.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fields/volume.hpp"
#include "rt/rope/path_check.hpp"

namespace visvol::cli {

// Time a mission holds the aircraft still (a multirotor's LOITER_TIME: it
// hovers), which the path's length at the vehicle's speed does not count: in
// all, and in sight of each constraint point (by its sight line at the
// vertex held).
struct Holds {
  double total_s = 0;
  std::vector<double> in_sight_s;  // per constraint
};

// {"constraints": [{kind, point, eye_m, satisfied_fraction, seen_m, exposure_s, met}],
//  "envelope": [{name, unit, limit, worst, satisfied_fraction, met}],
//  "inside_planning_bounds", "inside_bounds_fraction", "all_met", "unmet": [...],
//  "length_m", "duration_s", "held_s", "fc"}; infinite limits are null. Durations
// and exposures count `holds` (none for a plan).
// `more_unmet`: requirements beyond the path's own that are unmet (a
// landing's approach circle under the clearance): in "unmet", and
// "all_met" false.
nlohmann::json check_json(const rt::PathCheck& check, const rt::VehicleEnvelope& envelope, const Holds& holds = {},
                          const std::vector<std::string>& more_unmet = {});

// Per vertex: x_m, y_m, z_m, fp, ground_m, clearance_m, early_m (null where none), climb_deg,
// turn_radius_m, seen_by.
// (climb_deg is the straight segment's to the next vertex; a fixed-wing's arc
// by a corner may climb more steeply, and max-climb's worst includes it.)
nlohmann::json vertices_json(const rt::PathCheck& check, const std::vector<rt::Vec3>& path);

// Lines "constraint  hidden-from (x, y, z): met on 1.000 of the length" and
// "envelope   max-climb 15.0 deg: worst 12.3 deg, met", then "requirements  all met"
// or "requirements  NOT MET: ..." (with `more_unmet`, as check_json).
void print_check(const rt::PathCheck& check, const rt::VehicleEnvelope& envelope, const Holds& holds = {},
                 const std::vector<std::string>& more_unmet = {});

// The flights of a PX4 fixed-wing (rt::PathChecker::fly): [{ground_speed_m_per_s,
// switch_distance_m, altitude_hold_m, length_m, least_clearance_m, least_at:
// {x_m, y_m, z_m}, clearance_fraction, max_off_path_m, constraint_fractions:
// [...], reached_end}].
nlohmann::json flown_json(const std::vector<rt::FlownCheck>& flights);

// Lines "flown      PX4 L1 guidance at 25.0 m/s over the ground, waypoints
// taken 119 m out, heights held 119 m early" under print_check's: the least clearance and where, how
// far off the legs (the clearance is the "flown-clearance" requirement),
// each constraint's share of the flown length (a report).
void print_flown(const std::vector<rt::FlownCheck>& flights, const rt::PathCheck& check,
                 const rt::VehicleEnvelope& envelope);

// A landing's loiter circle (`radius_m` around (x, y) at `altitude_m`, the
// DEM's datum): its least height over the finest terrain `ground_m(x, y)`,
// sampled a sixteenth of a post apart as the path's check samples;
// -infinity where it leaves the grid `g` (terrain the pack does not know).
double circle_clearance_m(const std::function<double(double, double)>& ground_m, const fields::VolumeGeometry& g,
                          double x, double y, double altitude_m, double radius_m);

}  // namespace visvol::cli
