// The straightforward field sampler, as it was before the sampler found each
// column's tiles once per query: every post, voxel and band sample read
// through the level's post(), voxel() and tff(). Kept for the tests that
// check the faster paths against it value for value.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"

namespace visvol::fields::testing {

template <class Level>
class ReferenceSampler {
 public:
  explicit ReferenceSampler(const Level& level) : level_(&level) {}

  double height(double x, double y) const {
    const Cell c = cell_xy(x, y);
    return lerp(lerp(post(c.i, c.j), post(c.i + 1, c.j), c.fi), lerp(post(c.i, c.j + 1), post(c.i + 1, c.j + 1), c.fi),
                c.fj);
  }

  double visibility(double x, double y, double z) const {
    const VolumeGeometry& g = level_->geometry();
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

  Eigen::Vector3d gradient(double x, double y, double z) const {
    const VolumeGeometry& g = level_->geometry();
    const Cell c = cell_xy(x, y);
    const double ground = lerp(lerp(post(c.i, c.j), post(c.i + 1, c.j), c.fi),
                               lerp(post(c.i, c.j + 1), post(c.i + 1, c.j + 1), c.fi), c.fj);
    if (z <= ground) return Eigen::Vector3d::Zero();
    const double gk = (z - g.z0_m) / g.dz_m;
    if (gk < 0) return Eigen::Vector3d::Zero();
    const double kc = std::min(gk, static_cast<double>(g.nz - 1));
    const int k = std::min(static_cast<int>(kc), g.nz - 2);
    const double fk = kc - k;
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
          const int a = 1 + di, b = 1 + dj, kk = k + dk;
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

  TffSample terrain_force(double x, double y, double z) const {
    const TffParams& p = level_->tff_params();
    const Cell c = cell_xy(x, y);
    const double step = p.step_m();
    TffSample out;
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        const double w = (di ? c.fi : 1 - c.fi) * (dj ? c.fj : 1 - c.fj);
        if (w == 0) continue;
        const int i = c.i + di, j = c.j + dj;
        const double b =
            std::clamp((z - post(i, j) + p.band_offset_m) / step, 0.0, static_cast<double>(p.band_levels - 1));
        const int b0 = std::min(static_cast<int>(b), p.band_levels - 2);
        const double fb = b - b0;
        const TffSample lo = level_->tff(i, j, b0), hi = level_->tff(i, j, b0 + 1);
        auto mix = [&](float a0, float a1) { return static_cast<float>(w * (a0 + fb * (a1 - a0))); };
        out.dx_m += mix(lo.dx_m, hi.dx_m);
        out.dy_m += mix(lo.dy_m, hi.dy_m);
        out.dz_m += mix(lo.dz_m, hi.dz_m);
        out.signed_distance_m += mix(lo.signed_distance_m, hi.signed_distance_m);
      }
    }
    return out;
  }

 private:
  struct Cell {
    int i, j;
    double fi, fj;
  };
  Cell cell_xy(double x, double y) const {
    const VolumeGeometry& g = level_->geometry();
    const double gi = std::clamp((x - g.origin_x) / g.spacing_m, 0.0, double(g.nx - 1));
    const double gj = std::clamp((g.origin_y - y) / g.spacing_m, 0.0, double(g.ny - 1));
    const int i = std::min(static_cast<int>(gi), g.nx - 2);
    const int j = std::min(static_cast<int>(gj), g.ny - 2);
    return {i, j, gi - i, gj - j};
  }
  double post(int i, int j) const { return level_->post(i, j); }
  double voxel(int i, int j, int k) const { return level_->voxel(i, j, k); }
  static double lerp(double a, double b, double t) { return a + t * (b - a); }

  const Level* level_;
};

}  // namespace visvol::fields::testing
