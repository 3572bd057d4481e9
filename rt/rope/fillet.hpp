// The arc a fixed-wing flies by a vertex on: what rt::PathChecker samples
// inside each corner and rt::fit_to_envelope holds its band along.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <optional>

#include "rt/rope/path_metrics.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

// The arc a fixed-wing flies through vertex b, from segment a-b to b-c, at
// `radius_m` (fly-by: tangent to both segments, inside the corner), or at
// the largest radius half of each segment leaves room for; heights follow
// the segments' halves. None for a straight continuation, a repeated spot
// or no radius.
struct Fillet {
  Eigen::Vector2d centre;
  double radius_m = 0, start_rad = 0, turn_rad = 0, sense = 1;  // sense +1 counter-clockwise
  double z_start_m = 0, z_end_m = 0;
  double length_m() const { return radius_m * turn_rad; }
  // The point a fraction f (0..1) along the arc.
  Vec3 at(double f) const {
    const double angle = start_rad + sense * turn_rad * f;
    return {centre.x() + radius_m * std::cos(angle), centre.y() + radius_m * std::sin(angle),
            z_start_m + (z_end_m - z_start_m) * f};
  }
};

inline std::optional<Fillet> fillet(const Vec3& a, const Vec3& b, const Vec3& c, double radius_m) {
  const Eigen::Vector2d u(b.x() - a.x(), b.y() - a.y()), w(c.x() - b.x(), c.y() - b.y());
  const double lu = u.norm(), lw = w.norm();
  if (!(radius_m > 0) || lu < kSameSpotM || lw < kSameSpotM) return std::nullopt;
  const double turn = std::acos(std::clamp(u.dot(w) / (lu * lw), -1.0, 1.0));
  if (turn < 1e-6) return std::nullopt;
  const double t = std::tan(0.5 * std::min(turn, M_PI - 1e-6));
  const double d = std::min(radius_m * t, 0.5 * std::min(lu, lw));  // from the vertex to each tangent point
  Fillet f;
  f.radius_m = d / t;
  f.turn_rad = turn;
  f.sense = u.x() * w.y() - u.y() * w.x() > 0 ? 1.0 : -1.0;
  const Eigen::Vector2d start = Eigen::Vector2d(b.x(), b.y()) - u / lu * d;
  const Eigen::Vector2d inward = f.sense * Eigen::Vector2d(-u.y(), u.x()) / lu;  // towards the turn's centre
  f.centre = start + inward * f.radius_m;
  f.start_rad = std::atan2(start.y() - f.centre.y(), start.x() - f.centre.x());
  f.z_start_m = b.z() - (b.z() - a.z()) * d / lu;
  f.z_end_m = b.z() + (c.z() - b.z()) * d / lw;
  return f;
}

}  // namespace visvol::rt
