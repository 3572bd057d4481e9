// The arc of a fixed-wing that turns at its radius by a vertex: what
// rt::PathChecker samples inside each corner and rt::fit_to_envelope holds
// its band along (an autopilot that switches early cuts deeper:
// rt/rope/l1_track.hpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "fields/heightfield.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/rope.hpp"
#include "rt/rope/terrain_probe.hpp"

namespace visvol::rt {

// The arc a fixed-wing flies by a corner on: tangent to the segment in and
// the segment out, inside the corner, at a radius; heights follow the two
// segments.
struct Fillet {
  Eigen::Vector2d centre;
  double radius_m = 0, start_rad = 0, turn_rad = 0, sense = 1;  // sense +1 counter-clockwise
  double z_start_m = 0, z_end_m = 0;
  // The least share of a move of the corner's height that the arc's heights
  // follow (1 - the tangent points' distance from the corner over the
  // segment's length, the smaller of the two; 0 where an arc spans a segment).
  double corner_share = 1;
  double length_m() const { return radius_m * turn_rad; }
  // The point a fraction f (0..1) along the arc.
  Vec3 at(double f) const {
    const double angle = start_rad + sense * turn_rad * f;
    return {centre.x() + radius_m * std::cos(angle), centre.y() + radius_m * std::sin(angle),
            z_start_m + (z_end_m - z_start_m) * f};
  }
};

// The share of its legs' slope an arc turning `turn_rad` climbs at
// (theta / (2 tan(theta / 2)), 1 for no turn): it is shorter than the legs
// it cuts, so legs within this share of a slope limit keep their arc within
// the limit (rt::fit_to_envelope's legs by a corner, a loiter's chords).
inline double arc_slope_share(double turn_rad) {
  if (!(turn_rad > 1e-9)) return 1.0;
  return turn_rad / (2.0 * std::tan(0.5 * std::min(turn_rad, M_PI - 1e-6)));
}

// The arc from segment a-b_in to b_out-c (b_in and b_out one spot: the same
// vertex, or the ends of a run on it) at `radius_m`, its tangent points no
// farther from the corner than the segments are long. None for a
// straight continuation or no radius.
inline std::optional<Fillet> fillet(const Vec3& a, const Vec3& b_in, const Vec3& b_out, const Vec3& c,
                                    double radius_m) {
  const Eigen::Vector2d u(b_in.x() - a.x(), b_in.y() - a.y()), w(c.x() - b_out.x(), c.y() - b_out.y());
  const double lu = u.norm(), lw = w.norm();
  if (!(radius_m > 0) || lu < kSameSpotM || lw < kSameSpotM) return std::nullopt;
  const double turn = std::acos(std::clamp(u.dot(w) / (lu * lw), -1.0, 1.0));
  if (turn < 1e-6) return std::nullopt;
  const double t = std::tan(0.5 * std::min(turn, M_PI - 1e-6));
  const double d = std::min({radius_m * t, lu, lw});  // from the corner to each tangent point
  Fillet f;
  f.radius_m = d / t;
  f.turn_rad = turn;
  f.sense = u.x() * w.y() - u.y() * w.x() > 0 ? 1.0 : -1.0;
  const Eigen::Vector2d start = Eigen::Vector2d(b_in.x(), b_in.y()) - u / lu * d;
  const Eigen::Vector2d inward = f.sense * Eigen::Vector2d(-u.y(), u.x()) / lu;  // towards the turn's centre
  f.centre = start + inward * f.radius_m;
  f.start_rad = std::atan2(start.y() - f.centre.y(), start.x() - f.centre.x());
  f.z_start_m = b_in.z() - (b_in.z() - a.z()) * d / lu;
  f.z_end_m = b_out.z() + (c.z() - b_out.z()) * d / lw;
  f.corner_share = 1.0 - d / std::min(lu, lw);
  return f;
}

// The arcs a fixed-wing of turns no tighter than `min_radius_m` flies by a
// path's corners on, one per corner at the first vertex of its spot (a run
// of vertices within kSameSpotM horizontally is one corner, as in
// turn_radii_m): each at the smaller of min_radius_m and the radius the
// corner's segments leave room for (turn_radii_m's, the radius a check
// judges flyable). None where the path runs straight, and none at all
// without a turn limit.
inline std::vector<std::optional<Fillet>> corner_fillets(const Vec3* v, int count, double min_radius_m) {
  const std::size_t n = count > 0 ? static_cast<std::size_t>(count) : 0;
  std::vector<std::optional<Fillet>> out(n);
  if (!(min_radius_m > 0) || n < 3) return out;
  const std::vector<double> room = turn_radii_m(v, count);
  for (std::size_t first = 1; first + 1 < n;) {
    std::size_t last = first;  // the run of vertices on this spot
    while (last + 1 < n && same_spot(v[last + 1], v[first])) ++last;
    if (last + 1 >= n) break;              // the path's end
    const std::size_t before = first - 1;  // the spot before: its last vertex
    if (same_spot(v[before], v[first])) {  // the run started at the path's start
      first = last + 1;
      continue;
    }
    const double radius = std::min(min_radius_m, room[first]);
    out[first] = fillet(v[before], v[first], v[last], v[last + 1], radius);
    first = last + 1;
  }
  return out;
}

// Calls sample(p) at the k - 1 points that split a fillet into k equal arcs
// (its ends lie on the segments, sampled there), and probe(p, u) where the
// height above the bilinear terrain is extreme along each of the k chords
// between them (for_each_terrain_probe): what the checker judges on an arc,
// and the envelope fit holds its band at.
template <class Sample, class Probe>
inline void for_each_arc_point(const Fillet& f, int k, const fields::Heightfield& t, Sample sample, Probe probe) {
  for (int q = 1; q < k; ++q) sample(f.at(static_cast<double>(q) / k));
  for (int q = 0; q < k; ++q) {
    for_each_terrain_probe(t, f.at(static_cast<double>(q) / k), f.at(static_cast<double>(q + 1) / k), probe);
  }
}

}  // namespace visvol::rt
