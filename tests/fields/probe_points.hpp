// Points that probe a sampler where its shortcuts could go wrong: anywhere on
// the grid and a little beyond it, on and beside tile and brick edges (every
// 16 and 64 posts), exactly on posts; at, just above, just below and well
// below the terrain, between levels, above the top level and below level 0.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "fields/volume.hpp"

namespace visvol::fields::testing {

// `ground(x, y)` is the terrain height there (the sampler's own height()).
template <class Ground>
std::vector<Eigen::Vector3d> probe_points(const VolumeGeometry& g, const Ground& ground, int count,
                                          std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto pick = [&](int n) { return static_cast<int>(u(rng) * n); };
  // a grid coordinate along an axis of n posts
  auto coordinate = [&](int n) -> double {
    switch (pick(5)) {
      case 0: return -2.0 + u(rng) * (n + 3.0);  // anywhere, a little outside too
      case 1: {                                  // beside a brick edge
        const int edge = 16 * (1 + pick(std::max(1, (n - 1) / 16)));
        const double offsets[] = {-1.5, -1.0, -0.5, -1e-9, 0.0, 1e-9, 0.25, 0.5, 1.0};
        return edge + offsets[pick(9)];
      }
      case 2: return 64.0 * pick(n / 64 + 1) + (u(rng) - 0.5) * 3.0;  // beside a height tile edge
      case 3: return static_cast<double>(pick(n));                    // on a post
      default: return (n - 1) + (u(rng) - 0.5) * 3.0;                 // the far edge
    }
  };
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int n = 0; n < count; ++n) {
    const double x = g.origin_x + coordinate(g.nx) * g.spacing_m;
    const double y = g.origin_y - coordinate(g.ny) * g.spacing_m;
    const double h = ground(x, y);
    double z = 0;
    switch (pick(8)) {
      case 0: z = h; break;                                  // exactly on the terrain
      case 1: z = h - u(rng) * 3.0 * g.dz_m; break;          // in it
      case 2: z = h + 1e-7; break;                           // just above
      case 3: z = g.z_of(pick(g.nz)); break;                 // on a level
      case 4: z = g.top_m() + u(rng) * 3.0 * g.dz_m; break;  // above the top level
      case 5: z = g.z0_m - u(rng) * 2.0 * g.dz_m; break;     // below level 0
      default: z = h + u(rng) * 6.0 * g.dz_m; break;         // the first few levels above ground
    }
    out.emplace_back(x, y, z);
  }
  return out;
}

}  // namespace visvol::fields::testing
