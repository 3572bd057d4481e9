// The terrain force field (paper, Fig. 5): what keeps the rope off the ground.
//
// In a band of fixed offset around the terrain, every sample stores its
// outward displacement from the nearest point of the triangulated terrain
// (each grid cell split into two triangles along its north-west to south-east
// diagonal) and its signed distance (negative inside the terrain). The rope
// turns that into a repulsion along the displacement, strong inside.
//
// Band sample b of column (i, j) is at height
//   post(i, j) - band_offset_m + b * step,  step = 2 * band_offset_m / (band_levels - 1),
// so the band follows the terrain. Units: metres; displacement in world axes
// (x east, y north, z up).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "base/status.hpp"
#include "fields/heightfield.hpp"

namespace visvol::fields {

class WorkerPool;

// Band samples a column may have, and how far the band may reach, m: from a
// metre (a band that shrinks to nothing would leave the rope no push off the
// ground) to 300 m (the pack's centimetres in 16 bits).
inline constexpr int kMaxBandLevels = 64;
inline constexpr double kMinBandOffsetM = 1.0;
inline constexpr double kMaxBandOffsetM = 300.0;

struct TffParams {
  double band_offset_m = 100.0;  // band from terrain - offset to terrain + offset
  int band_levels = 24;          // samples per column (even: no sample sits on a post)
  double step_m() const { return 2.0 * band_offset_m / (band_levels - 1); }
};

Status validate(const TffParams& params);

// The posts of `spacing_m` a band sample's nearest-point search may reach
// (the band's offset, rounded up, and one): it meets every cell within that,
// so its cost grows with the square (a 100 m band over 1 cm posts built a
// 9.5 GB table of cells and ran for hours on a 64 x 64 DEM).
inline constexpr int kMaxTffReachPosts = 256;
int tff_reach_posts(const TffParams& params, double spacing_m);
// validate(params), and its reach at this spacing at most kMaxTffReachPosts.
Status validate(const TffParams& params, double spacing_m);

struct TffSample {
  float dx_m = 0, dy_m = 0, dz_m = 0;  // outward displacement from the nearest terrain point
  float signed_distance_m = 0;         // |displacement|, negative inside the terrain
};

struct NearestTerrainPoint {
  Eigen::Vector3d point_m;  // world x, y and height
  double distance_m = 0;
};

// The nearest point of the triangulated terrain to a world point, searching
// every triangle within `search_m` horizontally (a search radius of at least
// the true distance gives the exact answer). For tests, pass a radius that
// covers the grid.
NearestTerrainPoint nearest_terrain_point(const Heightfield& hf, const Eigen::Vector3d& q_m, double search_m);

// The band samples of rows [j_begin, j_end): out[((j - j_begin) * band_levels + b) * nx + i],
// for parameters validate() accepts (others write nothing).
// Each search is bounded by the sample's vertical distance to its own post,
// which the nearest point can never exceed, so the result is exact. A
// column's samples are searched together, in the lanes of a vector.
void terrain_force_rows(const Heightfield& hf, const TffParams& params, int j_begin, int j_end, TffSample* out,
                        WorkerPool* pool);

// The same rows at the baseline's width (2 lanes) whatever the CPU (4 lanes
// with AVX2 or AVX-512), one thread: tests hold the two to the same distances.
void terrain_force_rows_baseline(const Heightfield& hf, const TffParams& params, int j_begin, int j_end,
                                 TffSample* out);

}  // namespace visvol::fields
