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
// and optionally, to find a column's tiles once for the many reads a query
// makes of it (otherwise every read goes through voxel() and tff(), or for a
// level that gives its dense volume as field(), through that):
//   Column column(int i, int j) const;  // float voxel(int k); TffSample tff(int b)
//
// Real-time safe: no allocation, no locks; cost O(1) (a gradient reads 12
// posts and up to 32 voxels of 12 columns). Thread-safe for concurrent reads.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

#include "fields/heightfield.hpp"
#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// v clamped to [lo, hi], NaN to lo: a query at a non-finite point reads the
// grid's corner instead of indexing outside it (the rope's state guard,
// rt/rope, catches the NaN itself).
inline double clamp_index(double v, double lo, double hi) { return v > lo ? (v < hi ? v : hi) : lo; }

// What a force model reads at one point (FieldSampler::sample): the terrain
// height, and where asked for, grad F_p and the terrain force sample.
struct PointSample {
  double height_m = 0;
  Eigen::Vector3d gradient_per_m = Eigen::Vector3d::Zero();
  TffSample tff;
};

namespace detail {

// A column of a level without column(): each read looks its tile up again.
template <class Level>
class LookupColumn {
 public:
  // Unset until assigned: a query's block holds sixteen columns, and
  // zeroing them showed in profiles.
  LookupColumn() = default;
  LookupColumn(const Level& level, int i, int j) : level_(&level), i_(i), j_(j) {}
  float voxel(int k) const { return level_->voxel(i_, j_, k); }
  TffSample tff(int b) const { return level_->tff(i_, j_, b); }

 private:
  const Level* level_;
  int i_, j_;
};

// A column of a level held as a dense volume (field() gives it): voxels at a
// stride from the column's first; band samples looked up.
template <class Level>
class DenseColumn {
 public:
  DenseColumn() = default;  // unset until assigned, as LookupColumn
  DenseColumn(const Level& level, int i, int j)
      : level_(&level),
        voxel0_(level.field().values.data() + level.field().geometry.index(i, j, 0)),
        stride_(level.field().geometry.index(0, 0, 1)),
        i_(i),
        j_(j) {}
  float voxel(int k) const { return voxel0_[static_cast<std::size_t>(k) * stride_]; }
  TffSample tff(int b) const { return level_->tff(i_, j_, b); }

 private:
  const Level* level_;
  const float* voxel0_;
  std::size_t stride_;
  int i_, j_;
};

// The level's own column() where it has one; a DenseColumn for a dense
// volume; else a LookupColumn.
template <class Level, class = void>
struct HasDenseField : std::false_type {};
template <class Level>
struct HasDenseField<Level, std::void_t<decltype(std::declval<const Level&>().field().values.data())>>
    : std::true_type {};

template <class Level, class = void>
struct ColumnOf {
  using type = std::conditional_t<HasDenseField<Level>::value, DenseColumn<Level>, LookupColumn<Level>>;
  static type get(const Level& level, int i, int j) { return type(level, i, j); }
};
template <class Level>
struct ColumnOf<Level, std::void_t<decltype(std::declval<const Level&>().column(0, 0))>> {
  using type = decltype(std::declval<const Level&>().column(0, 0));
  static type get(const Level& level, int i, int j) { return level.column(i, j); }
};

}  // namespace detail

// A level held in memory.
class DenseLevelView {
 public:
  DenseLevelView(const Heightfield& terrain, const DenseVolume& field) : terrain_(&terrain), field_(&field) {}
  const VolumeGeometry& geometry() const { return field_->geometry; }
  float post(int i, int j) const { return terrain_->at(i, j); }
  float voxel(int i, int j, int k) const { return field_->at(i, j, k); }
  const DenseVolume& field() const { return *field_; }

 private:
  const Heightfield* terrain_;
  const DenseVolume* field_;
};

template <class Level>
class FieldSampler {
 public:
  FieldSampler() = default;
  explicit FieldSampler(const Level& level) : level_(level), inv_dz_(1.0 / level_.geometry().dz_m) {}

  const Level& level() const { return level_; }

  // The grid cell under (x, y), clamped to the grid: what every query starts
  // from (a caller that needs it too, such as a sampler picking levels, can
  // find it once and pass it on).
  struct Cell {
    int i, j;       // lower corner, so that i + 1 and j + 1 are in the grid
    double fi, fj;  // fractions within the cell
  };
  Cell cell(double x, double y) const {
    const VolumeGeometry& g = level_.geometry();
    const double gi = clamp_index((x - g.origin_x) / g.spacing_m, 0.0, double(g.nx - 1));
    const double gj = clamp_index((g.origin_y - y) / g.spacing_m, 0.0, double(g.ny - 1));
    const int i = std::min(static_cast<int>(gi), g.nx - 2);
    const int j = std::min(static_cast<int>(gj), g.ny - 2);
    return {i, j, gi - i, gj - j};
  }

  // Terrain height under (x, y), m; clamped to the grid's edge outside it.
  double height(double x, double y) const { return height(cell(x, y)); }
  double height(const Cell& c) const {
    return lerp(lerp(post(c.i, c.j), post(c.i + 1, c.j), c.fi), lerp(post(c.i, c.j + 1), post(c.i + 1, c.j + 1), c.fi),
                c.fj);
  }

  // F_p at (x, y, z): 0 below the lowest level, the top level's value above it.
  double visibility(double x, double y, double z) const {
    const VolumeGeometry& g = level_.geometry();
    const double gk = (z - g.z0_m) / g.dz_m;
    if (gk < 0) return 0.0;
    const Cell c = cell(x, y);
    const double kc = clamp_index(gk, 0.0, static_cast<double>(g.nz - 1));
    const int k = std::min(static_cast<int>(kc), g.nz - 2);
    const double fk = kc - k;
    const Column c00 = column(c.i, c.j), c10 = column(c.i + 1, c.j);
    const Column c01 = column(c.i, c.j + 1), c11 = column(c.i + 1, c.j + 1);
    auto layer = [&](int kk) {
      return lerp(lerp(c00.voxel(kk), c10.voxel(kk), c.fi), lerp(c01.voxel(kk), c11.voxel(kk), c.fi), c.fj);
    };
    return lerp(layer(k), layer(k + 1), fk);
  }

  // grad F_p at (x, y, z), per metre; zero at and below the terrain.
  // The voxel gradients of the cell's eight corners, interpolated; each
  // column's first level above the terrain is found once for the query.
  Eigen::Vector3d gradient(double x, double y, double z) const {
    const Cell c = cell(x, y);
    Block block;
    read_centre(c, block);
    return gradient_in(c, block, ground(c, block), z);
  }

  // The terrain force field sample at (x, y, z): trilinear over the four
  // surrounding columns, each at its own band coordinate (the band follows
  // the terrain). Below the band it is the band's lowest sample, above it the
  // highest (signed distances there are -offset and +offset or beyond).
  TffSample terrain_force(double x, double y, double z) const {
    const Cell c = cell(x, y);
    Block block;
    read_centre(c, block);
    return terrain_force_in(c, block, z);
  }

  // height(), and gradient() and terrain_force() where asked for, at one
  // point: the cell's posts and columns are found once for all three. Each
  // value is exactly what its own call returns.
  PointSample sample(double x, double y, double z, bool with_gradient, bool with_terrain_force) const {
    return sample(cell(x, y), z, with_gradient, with_terrain_force);
  }
  PointSample sample(const Cell& c, double z, bool with_gradient, bool with_terrain_force) const {
    Block block;
    read_centre(c, block);
    PointSample s;
    s.height_m = ground(c, block);
    if (with_gradient) s.gradient_per_m = gradient_in(c, block, s.height_m, z);
    if (with_terrain_force) s.tff = terrain_force_in(c, block, z);
    return s;
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
  using Column = typename detail::ColumnOf<Level>::type;

  // The columns i - 1..i + 2, j - 1..j + 2 around a cell, [b][a] for column
  // (i - 1 + a, j - 1 + b): the centre 2 x 2 (the cell's corners) and the
  // ring of their neighbours that a gradient differences against. The four
  // corners of the block are never read and stay unset.
  struct Block {
    float post[4][4];       // terrain height, m (centre only until read_ring)
    int first_above[4][4];  // first level above the terrain; nz outside the grid
    Column col[4][4];
  };

  // The cell's four corner columns (always in the grid).
  void read_centre(const Cell& c, Block& block) const {
    for (int b = 1; b < 3; ++b) {
      for (int a = 1; a < 3; ++a) read_column(c.i - 1 + a, c.j - 1 + b, block.post[b][a], block.col[b][a]);
    }
  }

  // Their eight neighbours, for a gradient; nz (never above) outside the grid.
  void read_ring(const Cell& c, Block& block) const {
    const VolumeGeometry& g = level_.geometry();
    static constexpr int kRing[8][2] = {{1, 0}, {2, 0}, {0, 1}, {3, 1}, {0, 2}, {3, 2}, {1, 3}, {2, 3}};
    for (const auto& ab : kRing) {
      const int a = ab[0], b = ab[1], i = c.i - 1 + a, j = c.j - 1 + b;
      if (i < 0 || j < 0 || i >= g.nx || j >= g.ny) {
        block.first_above[b][a] = g.nz;
      } else {
        read_column(i, j, block.post[b][a], block.col[b][a]);
        block.first_above[b][a] = first_above(block.post[b][a]);
      }
    }
    for (int b = 1; b < 3; ++b)
      for (int a = 1; a < 3; ++a) block.first_above[b][a] = first_above(block.post[b][a]);
  }

  void read_column(int i, int j, float& post_m, Column& column_out) const {
    post_m = level_.post(i, j);
    column_out = column(i, j);
  }

  // The lowest level strictly above a post of height post_m:
  // floor((post_m - z0) / dz) + 1. A product with 1 / dz is within a few ulps
  // of the quotient (a division stalls the query a dozen times); only a
  // quotient that close to an integer can floor differently, and there the
  // division decides.
  int first_above(float post_m) const {
    const VolumeGeometry& g = level_.geometry();
    const double q = (post_m - g.z0_m) * inv_dz_;
    const int t = floor_to_int(q);
    if (q - t < 1e-9 || t + 1 - q < 1e-9) return floor_to_int((post_m - g.z0_m) / g.dz_m) + 1;
    return t + 1;
  }

  // static_cast<int>(std::floor(q)) in a few integer instructions (baseline
  // x86-64 has no floor instruction) for the range of level indices.
  static int floor_to_int(double q) {
    if (!(q > -1e9 && q < 1e9)) return static_cast<int>(std::floor(q));
    const int t = static_cast<int>(q);  // towards zero
    return q < t ? t - 1 : t;
  }

  // Terrain height at the cell's point, from the centre posts (as height()).
  static double ground(const Cell& c, const Block& block) {
    return lerp(lerp(block.post[1][1], block.post[1][2], c.fi), lerp(block.post[2][1], block.post[2][2], c.fi), c.fj);
  }

  // gradient() once the centre is read and the ground known.
  Eigen::Vector3d gradient_in(const Cell& c, Block& block, double ground_m, double z) const {
    const VolumeGeometry& g = level_.geometry();
    if (z <= ground_m) return Eigen::Vector3d::Zero();
    const double gk = (z - g.z0_m) / g.dz_m;
    if (gk < 0) return Eigen::Vector3d::Zero();
    const double kc = clamp_index(gk, 0.0, static_cast<double>(g.nz - 1));
    const int k = std::min(static_cast<int>(kc), g.nz - 2);
    const double fk = kc - k;
    read_ring(c, block);
    auto above = [&](int a, int b, int kk) { return kk >= 0 && kk < g.nz && kk >= block.first_above[b][a]; };
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int dk = 0; dk < 2; ++dk) {
      for (int dj = 0; dj < 2; ++dj) {
        for (int di = 0; di < 2; ++di) {
          const double w = (di ? c.fi : 1 - c.fi) * (dj ? c.fj : 1 - c.fj) * (dk ? fk : 1 - fk);
          const int a = 1 + di, b = 1 + dj, kk = k + dk;  // corner in the 4 x 4 block
          if (w == 0 || !above(a, b, kk)) continue;
          const double v = block.col[b][a].voxel(kk);
          // backward difference where that neighbour is above the terrain, else forward
          auto diff = [&](int ba, int bb, int bk, int fa, int fb, int fkk, double step) {
            if (above(ba, bb, bk)) return (v - block.col[bb][ba].voxel(bk)) / step;
            if (above(fa, fb, fkk)) return (block.col[fb][fa].voxel(fkk) - v) / step;
            return 0.0;
          };
          const double gx = diff(a - 1, b, kk, a + 1, b, kk, g.spacing_m);
          const double gy = -diff(a, b - 1, kk, a, b + 1, kk, g.spacing_m);
          const double gz = diff(a, b, kk - 1, a, b, kk + 1, g.dz_m);
          sum += w * Eigen::Vector3d(gx, gy, gz);
        }
      }
    }
    return sum;
  }

  // terrain_force() once the centre is read.
  TffSample terrain_force_in(const Cell& c, const Block& block, double z) const {
    const TffParams& p = level_.tff_params();
    const double step = p.step_m();
    TffSample out;
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        const double w = (di ? c.fi : 1 - c.fi) * (dj ? c.fj : 1 - c.fj);
        if (w == 0) continue;
        const float post_m = block.post[1 + dj][1 + di];
        const Column& col = block.col[1 + dj][1 + di];
        const double b =
            clamp_index((z - post_m + p.band_offset_m) / step, 0.0, static_cast<double>(p.band_levels - 1));
        const int b0 = std::min(static_cast<int>(b), p.band_levels - 2);
        const double fb = b - b0;
        const TffSample lo = col.tff(b0), hi = col.tff(b0 + 1);
        auto mix = [&](float a0, float a1) { return static_cast<float>(w * (a0 + fb * (a1 - a0))); };
        out.dx_m += mix(lo.dx_m, hi.dx_m);
        out.dy_m += mix(lo.dy_m, hi.dy_m);
        out.dz_m += mix(lo.dz_m, hi.dz_m);
        out.signed_distance_m += mix(lo.signed_distance_m, hi.signed_distance_m);
      }
    }
    return out;
  }

  bool in_grid(int i, int j, int k) const {
    const VolumeGeometry& g = level_.geometry();
    return i >= 0 && j >= 0 && k >= 0 && i < g.nx && j < g.ny && k < g.nz;
  }
  bool above(int i, int j, int k) const { return level_.geometry().z_of(k) > static_cast<double>(level_.post(i, j)); }
  Column column(int i, int j) const { return detail::ColumnOf<Level>::get(level_, i, j); }
  double post(int i, int j) const { return level_.post(i, j); }
  double voxel(int i, int j, int k) const { return level_.voxel(i, j, k); }
  static double lerp(double a, double b, double t) { return a + t * (b - a); }

  Level level_;
  double inv_dz_ = 0;  // 1 / dz_m
};

}  // namespace visvol::fields
