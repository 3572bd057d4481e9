// Building points' visibility hulls over a level's terrain: allocates
// (a copy of the terrain, its padding, each hull), so start-up, offline and
// builder-thread code only, never the 1 kHz loop.
#pragma once

#include "base/status.hpp"
#include "fields/heightfield.hpp"
#include "fields/hull_kernel.hpp"
#include "fields/volume.hpp"
#include "rt/rope/point_hull.hpp"

namespace visvol::rt {

// A level's terrain as a heightfield (a copy: allocates).
template <class Level>
fields::Heightfield level_terrain(const Level& level) {
  const fields::VolumeGeometry& g = level.geometry();
  fields::Heightfield hf;
  hf.nx = g.nx;
  hf.ny = g.ny;
  hf.spacing_m = g.spacing_m;
  hf.origin_x = g.origin_x;
  hf.origin_y = g.origin_y;
  hf.height_m.resize(hf.size());
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) hf.at(i, j) = level.post(i, j);
  return hf;
}

// Builds the hulls of points over one level's terrain (copied and padded once,
// so many observers pay for that once): every column's lowest height that
// sees the point (the point's own column and its neighbours see it from the
// ground up). A hull costs the horizon of the level's grid around the point
// (grid-only rings: 0.013 s for SF North's 370 x 466 posts). Refuses a point
// outside the grid or below the terrain, naming it. Offline: allocates.
class PointHullMaker {
 public:
  template <class Level>
  explicit PointHullMaker(const Level& level);
  Result<PointHull> operator()(const Vec3& p, const char* name) const;
  // Bytes held for a level of nx x ny posts (the terrain and its padding).
  static std::size_t bytes(int nx, int ny);

 private:
  fields::VolumeGeometry g_;
  fields::Heightfield hf_;
  fields::PaddedTerrain padded_;
};

// One point's hull (a PointHullMaker for one use).
template <class Level>
Result<PointHull> point_hull(const Level& level, const Vec3& p, const char* name) {
  return PointHullMaker(level)(p, name);
}

// Grid-only horizons (fields::observer_horizon) reach at most a post past
// the grid: a padding of a few posts is enough.
template <class Level>
PointHullMaker::PointHullMaker(const Level& level)
    : g_(level.geometry()), hf_(level_terrain(level)), padded_(fields::pad_terrain(hf_, g_, 2)) {}

}  // namespace visvol::rt
