// Helpers that the executive's translation units share (executive.cpp, executive_commands.cpp,
// executive_reports.cpp). Private to rt/exec: not part of the executive's interface.
#pragma once

#include <cmath>
#include <string>

#include "base/status.hpp"
#include "fields/volume.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt::detail {

// Finite and over the grid: what every endpoint must be (real-time safe).
inline bool inside(const Vec3& p, const fields::VolumeGeometry& g) {
  const double x1 = g.origin_x + (g.nx - 1) * g.spacing_m, y0 = g.origin_y - (g.ny - 1) * g.spacing_m;
  return p.allFinite() && p.x() >= g.origin_x && p.x() <= x1 && p.y() >= y0 && p.y() <= g.origin_y;
}

// Whether every vertex of a rope is finite (real-time safe, O(vertices)).
inline bool finite_rope(const Rope& rope) {
  const Vec3* v = rope.vertices();
  double sum = 0;
  for (int i = 0; i <= rope.segments(); ++i) sum += v[i].x() + v[i].y() + v[i].z();
  return std::isfinite(sum);
}

inline Status check_point(const char* name, const Vec3& p, const fields::VolumeGeometry& g, double ground_m) {
  const double x1 = g.origin_x + (g.nx - 1) * g.spacing_m, y0 = g.origin_y - (g.ny - 1) * g.spacing_m;
  if (!inside(p, g)) {
    return invalid_argument(std::string(name) + ": (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                            ") is outside the pack (x " + std::to_string(g.origin_x) + ".." + std::to_string(x1) +
                            ", y " + std::to_string(y0) + ".." + std::to_string(g.origin_y) + ")");
  }
  if (p.z() < ground_m) {
    return invalid_argument(std::string(name) + ": " + std::to_string(ground_m - p.z()) + " m below the terrain");
  }
  return {};
}

}  // namespace visvol::rt::detail
