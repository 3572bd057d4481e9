// Sampling one level of detail at world points: terrain height (bilinear), F_p
// (trilinear) and its gradient.
//
// The gradient follows the paper: backward differences between voxels above the
// terrain (a forward difference where the backward neighbour is at or below the
// terrain), zero at and below the terrain; interpolated trilinearly between
// voxels. Units: F_p is dimensionless, the gradient is per metre in world axes
// (x east, y north, z up).
//
// `Level` provides the data (a dense level in memory, or a pack's tiles):
//   const VolumeGeometry& geometry() const;
//   float post(int i, int j) const;          // terrain height, m
//   float voxel(int i, int j, int k) const;  // F_p
// and, for terrain_force() only:
//   TffSample tff(int i, int j, int b) const;
//   const TffParams& tff_params() const;
//
// Real-time safe: no allocation, no locks; cost O(1) (about 60 reads for a
// gradient). Thread-safe for concurrent reads.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "fields/heightfield.hpp"
#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// A level held in memory.
class DenseLevelView {
 public:
  DenseLevelView(const Heightfield& terrain, const DenseVolume& field)
      : terrain_(&terrain), field_(&field) {}
  const VolumeGeometry& geometry() const { return field_->geometry; }
  float post(int i, int j) const { return terrain_->at(i, j); }
  float voxel(int i, int j, int k) const { return field_->at(i, j, k); }

 private:
  const Heightfield* terrain_;
  const DenseVolume* field_;
};

template <class Level>
class FieldSampler {
 public:
  FieldSampler() = default;
  explicit FieldSampler(const Level& level) : level_(level) {}

  const Level& level() const { return level_; }

  // Terrain height under (x, y), m; clamped to the grid's edge outside it.
  double height(double x, double y) const {
    const Cell c = cell_xy(x, y);
    return lerp(lerp(post(c.i, c.j), post(c.i + 1, c.j), c.fi),
                lerp(post(c.i, c.j + 1), post(c.i + 1, c.j + 1), c.fi), c.fj);
  }

  // F_p at (x, y, z): 0 below the lowest level, the top level's value above it.
  double visibility(double x, double y, double z) const {
    const VolumeGeometry& g = level_.geometry();
    const double gk = (z - g.z0_m) / g.dz_m;
    if (gk < 0) return 0.0;
    const Cell c = cell_xy(x, y);
    const double kc = std::min(gk, static_cast<double>(g.nz - 1));
    const int k = std::min(static_cast<int>(kc), g.nz - 2);
    const double fk = kc - k;
    auto layer = [&](int kk) {
      return lerp(lerp(voxel(c.i, c.j, kk), voxel(c.i + 1, c.j, kk), c.fi),
                  lerp(voxel(c.i, c.j + 1, kk), voxel(c.i + 1, c.j + 1, kk), c.fi), c.fj);
    };
    return lerp(layer(k), layer(k + 1), fk);
  }

  // grad F_p at (x, y, z), per metre; zero at and below the terrain.
  // The voxel gradients of the cell's eight corners, interpolated; each
  // column's first level above the terrain is found once for the query.
  Eigen::Vector3d gradient(double x, double y, double z) const {
    const VolumeGeometry& g = level_.geometry();
    const Cell c = cell_xy(x, y);
    const double ground = lerp(lerp(post(c.i, c.j), post(c.i + 1, c.j), c.fi),
                               lerp(post(c.i, c.j + 1), post(c.i + 1, c.j + 1), c.fi), c.fj);
    if (z <= ground) return Eigen::Vector3d::Zero();
    const double gk = (z - g.z0_m) / g.dz_m;
    if (gk < 0) return Eigen::Vector3d::Zero();
    const double kc = std::min(gk, static_cast<double>(g.nz - 1));
    const int k = std::min(static_cast<int>(kc), g.nz - 2);
    const double fk = kc - k;
    // first level above the terrain for columns i-1..i+2, j-1..j+2 (nz outside)
    int first_above[4][4];
    for (int b = 0; b < 4; ++b) {
      for (int a = 0; a < 4; ++a) {
        const int i = c.i - 1 + a, j = c.j - 1 + b;
        first_above[b][a] = (i < 0 || j < 0 || i >= g.nx || j >= g.ny)
                                ? g.nz
                                : static_cast<int>(std::floor((post(i, j) - g.z0_m) / g.dz_m)) + 1;
      }
    }
    auto above = [&](int a, int b, int kk) { return kk >= 0 && kk < g.nz && kk >= first_above[b][a]; };
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int dk = 0; dk < 2; ++dk) {
      for (int dj = 0; dj < 2; ++dj) {
        for (int di = 0; di < 2; ++di) {
          const double w = (di ? c.fi : 1 - c.fi) * (dj ? c.fj : 1 - c.fj) * (dk ? fk : 1 - fk);
          const int a = 1 + di, b = 1 + dj, kk = k + dk;  // corner in the 4 x 4 block
          if (w == 0 || !above(a, b, kk)) continue;
          const int i = c.i + di, j = c.j + dj;
          const double v = voxel(i, j, kk);
          auto diff = [&](int ba, int bb, int bk, int fa, int fb, int fkk, int bi, int bj, int fi, int fj,
                          double step) {
            if (above(ba, bb, bk)) return (v - voxel(bi, bj, bk)) / step;
            if (above(fa, fb, fkk)) return (voxel(fi, fj, fkk) - v) / step;
            return 0.0;
          };
          const double gx = diff(a - 1, b, kk, a + 1, b, kk, i - 1, j, i + 1, j, g.spacing_m);
          const double gy = -diff(a, b - 1, kk, a, b + 1, kk, i, j - 1, i, j + 1, g.spacing_m);
          const double gz = diff(a, b, kk - 1, a, b, kk + 1, i, j, i, j, g.dz_m);
          sum += w * Eigen::Vector3d(gx, gy, gz);
        }
      }
    }
    return sum;
  }

  // The terrain force field sample at (x, y, z): trilinear over the four
  // surrounding columns, each at its own band coordinate (the band follows
  // the terrain). Below the band it is the band's lowest sample, above it the
  // highest (signed distances there are -offset and +offset or beyond).
  TffSample terrain_force(double x, double y, double z) const {
    const TffParams& p = level_.tff_params();
    const Cell c = cell_xy(x, y);
    const double step = p.step_m();
    TffSample out;
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        const double w = (di ? c.fi : 1 - c.fi) * (dj ? c.fj : 1 - c.fj);
        if (w == 0) continue;
        const int i = c.i + di, j = c.j + dj;
        const double b = std::clamp((z - post(i, j) + p.band_offset_m) / step, 0.0,
                                    static_cast<double>(p.band_levels - 1));
        const int b0 = std::min(static_cast<int>(b), p.band_levels - 2);
        const double fb = b - b0;
        const TffSample lo = level_.tff(i, j, b0), hi = level_.tff(i, j, b0 + 1);
        auto mix = [&](float a0, float a1) { return static_cast<float>(w * (a0 + fb * (a1 - a0))); };
        out.dx_m += mix(lo.dx_m, hi.dx_m);
        out.dy_m += mix(lo.dy_m, hi.dy_m);
        out.dz_m += mix(lo.dz_m, hi.dz_m);
        out.signed_distance_m += mix(lo.signed_distance_m, hi.signed_distance_m);
      }
    }
    return out;
  }

  // The gradient at voxel (i, j, k), per metre in world axes.
  Eigen::Vector3d voxel_gradient(int i, int j, int k) const {
    const VolumeGeometry& g = level_.geometry();
    if (!above(i, j, k)) return Eigen::Vector3d::Zero();
    const double v = voxel(i, j, k);
    auto diff = [&](int bi, int bj, int bk, int fi, int fj, int fk, double step) {
      if (in_grid(bi, bj, bk) && above(bi, bj, bk)) return (v - voxel(bi, bj, bk)) / step;
      if (in_grid(fi, fj, fk) && above(fi, fj, fk)) return (voxel(fi, fj, fk) - v) / step;
      return 0.0;
    };
    const double gx = diff(i - 1, j, k, i + 1, j, k, g.spacing_m);
    // j grows southward: the world y derivative has the opposite sign.
    const double gy = -diff(i, j - 1, k, i, j + 1, k, g.spacing_m);
    const double gz = diff(i, j, k - 1, i, j, k + 1, g.dz_m);
    return {gx, gy, gz};
  }

 private:
  struct Cell {
    int i, j;       // lower corner, so that i + 1 and j + 1 are in the grid
    double fi, fj;  // fractions within the cell
  };

  Cell cell_xy(double x, double y) const {
    const VolumeGeometry& g = level_.geometry();
    const double gi = std::clamp((x - g.origin_x) / g.spacing_m, 0.0, double(g.nx - 1));
    const double gj = std::clamp((g.origin_y - y) / g.spacing_m, 0.0, double(g.ny - 1));
    const int i = std::min(static_cast<int>(gi), g.nx - 2);
    const int j = std::min(static_cast<int>(gj), g.ny - 2);
    return {i, j, gi - i, gj - j};
  }
  bool in_grid(int i, int j, int k) const {
    const VolumeGeometry& g = level_.geometry();
    return i >= 0 && j >= 0 && k >= 0 && i < g.nx && j < g.ny && k < g.nz;
  }
  bool above(int i, int j, int k) const {
    return level_.geometry().z_of(k) > static_cast<double>(level_.post(i, j));
  }
  double post(int i, int j) const { return level_.post(i, j); }
  double voxel(int i, int j, int k) const { return level_.voxel(i, j, k); }
  static double lerp(double a, double b, double t) { return a + t * (b - a); }

  Level level_;
};

}  // namespace visvol::fields
