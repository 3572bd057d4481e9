// The path a vehicle flies through a mission's loiters: what `visvol check`
// judges. A fixed-wing circles each loiter's point at its radius (the
// vehicle's min-turn-radius where the item leaves the radius to the
// autopilot), clockwise for a positive radius, joining the circle along the
// tangent from where it comes and leaving it along the tangent to where it
// goes (straight out, where that lies inside the circle). It flies
//   - LOITER_UNLIM (17) as one turn (it loiters until moved on),
//   - LOITER_TURNS (18) for its turns, LOITER_TIME (19) for its seconds at
//     the vehicle's speed,
//   - LOITER_TO_ALT (31) until its altitude is reached;
// and then on to the tangent towards the next vertex. Every loiter changes
// altitude at the vehicle's steepest climb or descent from the leg in on,
// and circles (more than its turns where it must) until it has reached its
// own. A multirotor hovers over the point (climbing or descending on the
// spot); a fixed-wing asked for a circle under a centimetre turns on the
// spot at that radius.
//
// The circle's points turn at the loiter's radius (the autopilot holds it,
// where the polygon's fillets would read a little under it). Its first and
// last points are judged by the geometry where the circle is joined or left
// along a tangent, and at the radius where it is joined from or left towards
// a point inside it (straight out or in: the overshoot a fixed-wing needs
// there is not flown here).
//
// Offline (allocates). Lengths in metres (pack CRS), angles in degrees.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "path_io.hpp"
#include "rt/rope/vehicle.hpp"

namespace visvol::cli {

struct FlownPath {
  std::vector<Vec3> points;
  // Per point: the turn radius the autopilot flies there (a loiter's), or
  // NaN where the path's geometry decides (rt::turn_radii_m).
  std::vector<double> turn_radius_m;
  // Per point: the file's vertex it is, or -1 on a loiter's circle.
  std::vector<int> vertex_of;
  // Per point: the seconds the aircraft stays there (a multirotor's
  // LOITER_TIME hover), 0 where it flies on.
  std::vector<double> hold_s;
  // One line per loiter: "mission.items[4]: 3.0 turns of 80 m clockwise at 120.0 m (108 points)".
  std::vector<std::string> loiters;
};

// Polygon step of a flown circle: 36 points a turn.
inline constexpr double kLoiterStepDeg = 10.0;
// Turns a loiter may take in a check (LOITER_TIME at a slow speed, a deep
// LOITER_TO_ALT spiral): more is refused.
inline constexpr double kMaxLoiterTurns = 1000.0;
// Points all loiters of a path may fly (each turn is 36): more is refused
// before any is checked.
inline constexpr std::size_t kMaxFlownPoints = 1000000;

// `file`'s points with its loiters flown by a vehicle of envelope `e`.
// Errc::invalid_argument naming the item for a loiter of more than
// kMaxLoiterTurns turns.
Result<FlownPath> fly_path(const PathFile& file, const rt::VehicleEnvelope& e);

}  // namespace visvol::cli
