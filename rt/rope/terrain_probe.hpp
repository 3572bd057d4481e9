// Where a straight segment's height above the bilinear terrain is extreme:
// what makes a path check's clearance exact (rt::PathChecker) and the
// envelope fit's hold (rt::fit_to_envelope) between their samples.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "fields/heightfield.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

// Calls probe(p, u) at the points of segment a-b where its height above the
// bilinear terrain can be extreme: the ends, every grid line it crosses (the
// terrain is one bilinear piece between them, quadratic along the segment)
// and, between them, the vertex of that quadratic. The lowest clearance and
// the highest height above the terrain along the segment are at those points,
// exactly, whatever the sample step. u is the point's parameter (0 at a, 1
// at b).
template <class Probe>
inline void for_each_terrain_probe(const fields::Heightfield& t, const Vec3& a, const Vec3& b, Probe probe) {
  if (!a.allFinite() || !b.allFinite()) return;
  const double ia = t.i_of(a.x()), ja = t.j_of(a.y()), ib = t.i_of(b.x()), jb = t.j_of(b.y());
  std::vector<double> cuts = {0.0, 1.0};
  // the grid lines crossed, those of the grid only: beyond it the terrain
  // is its border's, so at most nx + ny cuts whatever the segment's length
  auto add_lines = [&](double from, double to, int posts) {
    if (std::fabs(to - from) < 1e-12) return;
    const double lo = std::max(std::floor(std::min(from, to)) + 1, 0.0);
    const double hi = std::min(std::max(from, to), static_cast<double>(posts - 1) + 0.5);
    for (double k = lo; k < hi; ++k) cuts.push_back((k - from) / (to - from));
  };
  add_lines(ia, ib, t.nx);
  add_lines(ja, jb, t.ny);
  std::sort(cuts.begin(), cuts.end());
  auto at = [&](double u) { return Vec3(a + (b - a) * u); };
  auto height = [&](double u) {
    const Vec3 p = at(u);
    return p.z() - fields::bilinear_height(t, t.i_of(p.x()), t.j_of(p.y()));
  };
  probe(a, 0.0);
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double u0 = cuts[k], u1 = cuts[k + 1];
    if (u1 - u0 < 1e-12) continue;
    // the quadratic through the piece's ends and middle, in t in [-1, 1]
    const double um = 0.5 * (u0 + u1);
    const double h0 = height(u0), hm = height(um), h1 = height(u1);
    const double curve = 0.5 * (h0 + h1) - hm, slope = 0.5 * (h1 - h0);
    if (std::fabs(curve) > 1e-12) {
      const double vertex = -slope / (2.0 * curve);
      if (vertex > -1.0 && vertex < 1.0) {
        const double u = um + vertex * 0.5 * (u1 - u0);
        probe(at(u), u);
      }
    }
    probe(at(u1), u1);
  }
}

}  // namespace visvol::rt
