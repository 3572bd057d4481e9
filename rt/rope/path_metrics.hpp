// What a path is worth: the paper's visibility measure F_c and the flight
// metrics a planner reports.
//
//   F_c = sum over arc-length samples t_i of F_p(phi(t_i)) * omega(t_i) / samples,
// the discrete form of the paper's integral over the curve parameter t in
// [0, 1] with the parameter proportional to arc length: the importance-weighted
// mean of F_p along the path, so a longer path is not worth more by its length.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include "rt/rope/rope.hpp"

namespace visvol::rt {

// What the metrics need from the terrain and the field.
class PathField {
 public:
  virtual ~PathField() = default;
  virtual double visibility(const Vec3& p_m) const = 0;  // F_p
  virtual double terrain_height_m(double x, double y) const = 0;
};

struct PathMetrics {
  double fc = 0;  // F_c, importance-weighted mean F_p
  double length_m = 0;
  double min_clearance_m = 0;    // lowest height above the terrain (sampled)
  double max_climb_deg = 0;      // steepest ascent of a segment
  double max_descent_deg = 0;    // steepest descent of a segment (positive)
  double min_turn_radius_m = 0;  // tightest turn an autopilot flies at a waypoint (turn_radii_m)
};

// Importance along the path, t in [0, 1] by arc length; nullptr means 1.
using Importance = double (*)(double t);

// F_c alone, from `samples` arc-length samples (>= 2). Real-time safe.
double path_fc(const Vec3* vertices, int count, const PathField& field, int samples, Importance importance = nullptr);

// Every metric; clearance is sampled every `clearance_step_m` along the path.
// Offline: allocates (turn_radii_m).
PathMetrics path_metrics(const Vec3* vertices, int count, const PathField& field, int samples, double clearance_step_m,
                         Importance importance = nullptr);

// The largest turn radius flyable at each vertex of a path (horizontal
// plane): a fillet of radius R at a vertex turning by theta starts
// R tan(theta / 2) before it, and two fillets may not overlap, so every
// segment i of horizontal length L_i needs R (t_i + t_(i+1)) <= L_i with
// t = tan(theta / 2). A vertex's radius is the smaller of its two segments'
// bounds; straight vertices and the ends are infinite. Vertices closer than
// kSameSpotM horizontally are one spot (a repeated waypoint, a climb on the
// spot): each of them gets the turn between the segments either side of the
// run, which a vertex 1e-8 m from its neighbour does not make a hairpin of.
inline constexpr double kSameSpotM = 0.01;
inline bool same_spot(const Vec3& a, const Vec3& b) { return std::hypot(a.x() - b.x(), a.y() - b.y()) < kSameSpotM; }
std::vector<double> turn_radii_m(const Vec3* vertices, int count);

}  // namespace visvol::rt
