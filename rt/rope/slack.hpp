// Laying a rope longer than its initial path (an inextensible rope needs
// slack to move): the path is bent sideways along `half_waves` half sines, in
// the horizontal plane, until it is long enough, and kept a floor above the
// terrain and inside the field's volume. One half wave bows a straight start
// out to explore; many small ones keep the shape of a planned start (a global
// path already in its valleys) while giving every part of it room to move.
//
// Sideways, not up: above the field's top F_p has no gradient, and a rope
// lifted there (a kilometre-high arch for 30% slack over 10 km) spends its
// time coming back down instead of settling into the terrain.
//
// Real-time safe (bisection on the bend, no allocation), used by the planner
// and by the executive.
#pragma once

#include <algorithm>
#include <cmath>

#include "fields/volume.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

inline double polyline_length_m(const Vec3* p, int points) {
  double l = 0;
  for (int i = 1; i < points; ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

// Writes n + 1 points into `out`: base(i) for i = 0..n (the initial path,
// resampled; its ends are kept), bent sideways in `half_waves` (>= 1) until the polyline is
// `length_m` long where the volume leaves room, interior points kept
// `floor_m` above height(x, y) and inside `g`'s horizontal extent and below
// its top. Returns the length laid, metres (shorter than asked only when the
// volume is too narrow for the bend).
template <class Base, class Height>
double lay_with_slack(const Base& base, int n, int half_waves, double length_m, double floor_m,
                      const fields::VolumeGeometry& g, const Height& height, Vec3* out) {
  const double waves = std::max(half_waves, 1);
  const Vec3 a = base(0), b = base(n);
  Vec3 side(-(b.y() - a.y()), b.x() - a.x(), 0.0);
  side = side.norm() > 0 ? Vec3(side / side.norm()) : Vec3(Vec3::UnitX());
  const double x0 = g.origin_x, x1 = g.origin_x + (g.nx - 1) * g.spacing_m;
  const double y0 = g.origin_y - (g.ny - 1) * g.spacing_m, y1 = g.origin_y;
  const double top = g.top_m();
  // Bend towards the side with more room at the middle of the path.
  const Vec3 mid = base(n / 2);
  auto room = [&](const Vec3& dir) {
    const double rx = dir.x() > 0 ? (x1 - mid.x()) / dir.x() : dir.x() < 0 ? (x0 - mid.x()) / dir.x() : 1e300;
    const double ry = dir.y() > 0 ? (y1 - mid.y()) / dir.y() : dir.y() < 0 ? (y0 - mid.y()) / dir.y() : 1e300;
    return std::min(rx, ry);
  };
  if (room(-side) > room(side)) side = -side;
  auto lay = [&](double amplitude_m) {
    out[0] = a;
    out[n] = b;
    for (int i = 1; i < n; ++i) {
      const double t = static_cast<double>(i) / n;
      Vec3 p = base(i) + amplitude_m * std::sin(M_PI * waves * t) * side;
      p.x() = std::clamp(p.x(), x0, x1);
      p.y() = std::clamp(p.y(), y0, y1);
      p.z() = std::min(std::max(p.z(), height(p.x(), p.y()) + floor_m), std::max(top, p.z()));
      out[i] = p;
    }
    return polyline_length_m(out, n + 1);
  };
  const double straight = lay(0.0);
  if (straight >= length_m) return straight;
  double lo = 0, hi = length_m;  // a bend as wide as the rope is long is always enough where there is room
  for (int it = 0; it < 50; ++it) {
    const double m = 0.5 * (lo + hi);
    (lay(m) < length_m ? lo : hi) = m;
  }
  return lay(hi);
}

}  // namespace visvol::rt
