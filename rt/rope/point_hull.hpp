// A point's visibility hull (the constraint surface of "stay hidden from" and
// "stay visible to") as the forces read it, and the small rules around it:
// the post a point stands on, an observer's eye on a level, folding hulls of
// one kind. Reading a hull (at) is real-time safe; building one is not
// (rt/rope/point_hull_maker.hpp, offline and start-up code).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "fields/sampler.hpp"
#include "fields/volume.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

// The lowest visible height over every post of a level from one point: the
// constraint surface of "stay hidden from" and "stay visible to".
struct PointHull {
  int nx = 0, ny = 0;
  double origin_x = 0, origin_y = 0, spacing_m = 1;
  std::vector<float> height_m;          // ny rows of nx
  double at(double x, double y) const;  // bilinear, clamped to the grid
};

// The post a hull's point stands on: the nearest post of grid g to (x, y);
// false when there is none (outside the grid, or x or y not finite).
// point_hull's rule, for callers that check a point before asking for its hull.
inline bool hull_post(const fields::VolumeGeometry& g, const Vec3& p, int& i, int& j) {
  const double fi = std::floor((p.x() - g.origin_x) / g.spacing_m + 0.5);
  const double fj = std::floor((g.origin_y - p.y()) / g.spacing_m + 0.5);
  if (!(fi >= 0 && fj >= 0 && fi < g.nx && fj < g.ny)) return false;
  i = static_cast<int>(fi);
  j = static_cast<int>(fj);
  return true;
}

// An observer's eye on a level: at least a centimetre above the post it
// stands on there (a coarser level's post may stand higher than the finest
// terrain the point was accepted on).
template <class Level>
Vec3 eye_on_level(const Level& level, Vec3 eye) {
  int i = 0, j = 0;
  if (hull_post(level.geometry(), eye, i, j)) eye.z() = std::max(eye.z(), double(level.post(i, j)) + 0.01);
  return eye;
}

// Folds `hull` into `into` (the same grid) post by post: for hidden-from
// hulls the lowest (below it, hidden from all of them), for visible-to hulls
// the highest (above it, visible to all). Writes in place, never reallocates.
inline void fold_hull(PointHull& into, const PointHull& hull, bool hidden_from) {
  std::vector<float>& to = into.height_m;
  for (std::size_t k = 0; k < to.size(); ++k) {
    to[k] = hidden_from ? std::min(to[k], hull.height_m[k]) : std::max(to[k], hull.height_m[k]);
  }
}

inline double PointHull::at(double x, double y) const {
  const double gi = fields::clamp_index((x - origin_x) / spacing_m, 0.0, double(nx - 1));
  const double gj = fields::clamp_index((origin_y - y) / spacing_m, 0.0, double(ny - 1));
  const int i = std::min(static_cast<int>(gi), nx - 2), j = std::min(static_cast<int>(gj), ny - 2);
  const double fi = gi - i, fj = gj - j;
  auto h = [&](int a, int b) {
    return static_cast<double>(
        height_m[static_cast<std::size_t>(b) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(a)]);
  };
  return (1 - fj) * ((1 - fi) * h(i, j) + fi * h(i + 1, j)) + fj * ((1 - fi) * h(i, j + 1) + fi * h(i + 1, j + 1));
}

}  // namespace visvol::rt
