#include "fields/hull_kernel.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "fields/exact_visibility.hpp"
#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

TEST(HullKernel, RingIndexIsABijectionOntoEachRing) {
  for (int m = 1; m <= 9; ++m) {
    std::set<int> seen;
    for (int dy = -m; dy <= m; ++dy)
      for (int dx = -m; dx <= m; ++dx)
        if (std::max(std::abs(dx), std::abs(dy)) == m) seen.insert(ring_index(dx, dy, m));
    EXPECT_EQ(static_cast<int>(seen.size()), ring_size(m));
    EXPECT_EQ(*seen.begin(), 0);
    EXPECT_EQ(*seen.rbegin(), ring_size(m) - 1);
  }
}

TEST(HullKernel, StencilCellsLieOnThePreviousRingAroundTheSightLine) {
  const int stride = 1000;
  for (int m = 2; m <= 12; ++m) {
    std::vector<HullEntry> ring;
    append_ring_entries(m, 10.0, 0.0, RangeShape::none, 0.0, stride, ring);
    ASSERT_EQ(static_cast<int>(ring.size()), ring_size(m));
    for (const HullEntry& e : ring) {
      EXPECT_LT(e.a, ring_size(m - 1));
      EXPECT_LT(e.b, ring_size(m - 1));
      EXPECT_GE(e.t, 0.0f);
      EXPECT_LT(e.t, 1.0f);
      EXPECT_NEAR(e.d_m, 10.0 * std::hypot(double(e.dx), double(e.dy)), 1e-3);
      // The ring m-1 crossing is (m-1)/m of the way to the target.
      EXPECT_NEAR(1.0 / e.inv_d1, e.d_m * (m - 1.0) / m, 1e-3);
      // Its posts are the two cells of ring m-1 on either side of the sight line.
      auto decode = [&](std::int32_t off, int& ox, int& oy) {
        oy = static_cast<int>(std::lround(double(off) / stride));
        ox = off - oy * stride;
      };
      int ax, ay, bx, by;
      decode(e.ta, ax, ay);
      decode(e.tb, bx, by);
      EXPECT_EQ(std::max(std::abs(ax), std::abs(ay)), m - 1);
      EXPECT_EQ(std::max(std::abs(bx), std::abs(by)), m - 1);
      EXPECT_EQ(ring_index(ax, ay, m - 1), e.a);
      EXPECT_EQ(ring_index(bx, by, m - 1), e.b);
    }
  }
}

// Checks that the horizon gives R3's answer just above and below the hull for
// every target within `rings`.
void expect_horizon_is_exact(const Heightfield& hf, int radius, int exact_rings, int rings, double curvature) {
  VolumeGeometry g;
  g.nz = 10;
  g.dz_m = 10;
  const PaddedTerrain t = pad_terrain(hf, g, radius);
  const int pi = hf.nx / 2, pj = hf.ny / 2;
  const double eye = hf.at(pi, pj) + 2.0;
  std::vector<float> horizon;
  observer_horizon(t, radius, exact_rings, hf.spacing_m, curvature, pi, pj, eye, horizon);
  const int side = 2 * radius + 1;
  for (int dy = -rings; dy <= rings; ++dy) {
    for (int dx = -rings; dx <= rings; ++dx) {
      if (std::max(std::abs(dx), std::abs(dy)) < 2) continue;
      const double h = horizon[static_cast<std::size_t>((dy + radius) * side + dx + radius)];
      const double d = std::hypot(double(dx), double(dy)) * hf.spacing_m;
      const double hull = eye + d * h + curvature * d * d / (2 * kEarthRadiusM);
      EXPECT_TRUE(r3_visible(hf, pi, pj, eye, pi + dx, pj + dy, hull + 0.01, curvature)) << dx << "," << dy;
      EXPECT_FALSE(r3_visible(hf, pi, pj, eye, pi + dx, pj + dy, hull - 0.01, curvature)) << dx << "," << dy;
    }
  }
}

TEST(HullKernel, ExactRingsMatchR3EverywhereInside) {
  expect_horizon_is_exact(fractal(33, 7), 16, 16, 16, 0.0);
  expect_horizon_is_exact(two_prisms(33), 16, 12, 12, 0.0);
  expect_horizon_is_exact(fractal(33, 8, 400.0), 16, 16, 16, 0.85714);
}

// Grid-only horizons (point hulls, viewsheds) are the full square's at every
// grid target, bit for bit, reading no post more than one past the grid
// (posts beyond are made towering walls: a read there would change a
// horizon): observers in corners, on every edge, inside, on a non-square
// grid, with and without curvature, with exact rings and with the stencil,
// over the whole grid and within a radius shorter than it.
TEST(HullKernel, GridOnlyHorizonsEqualTheFullSquaresOnTheGrid) {
  Heightfield hf = fractal(41, 11, 300.0);
  hf.nx = 41;
  hf.ny = 29;  // the first 29 rows: not square
  hf.height_m.resize(hf.size());
  VolumeGeometry g;
  g.nz = 10;
  g.dz_m = 10;
  const int radius = std::max(hf.nx, hf.ny) - 1;
  const PaddedTerrain wide = pad_terrain(hf, g, radius);
  PaddedTerrain narrow = pad_terrain(hf, g, 2);
  for (int j = -narrow.pad; j < hf.ny + narrow.pad; ++j) {
    for (int i = -narrow.pad; i < hf.nx + narrow.pad; ++i) {
      if (i < -1 || j < -1 || i > hf.nx || j > hf.ny) narrow.height_m[narrow.index(i, j)] = 1e30f;
    }
  }
  const int observers[][2] = {{0, 0},   {40, 28}, {0, 28},  {40, 0}, {20, 0}, {0, 14},
                              {40, 14}, {20, 28}, {20, 14}, {7, 23}, {33, 5}};
  for (const int r : {radius, 9}) {
    const int side = 2 * r + 1;
    for (const double curvature : {0.0, 0.85714}) {
      for (const int exact_rings : {4, 64}) {
        for (const auto& o : observers) {
          const double eye = hf.at(o[0], o[1]) + 2.0;
          std::vector<float> full, grid;
          observer_horizon(wide, r, exact_rings, hf.spacing_m, curvature, o[0], o[1], eye, full);
          observer_horizon(narrow, r, exact_rings, hf.spacing_m, curvature, o[0], o[1], eye, grid, true);
          ASSERT_EQ(grid.size(), full.size());
          int outside_set = 0;
          for (int dy = -r; dy <= r; ++dy) {
            for (int dx = -r; dx <= r; ++dx) {
              const std::size_t k = static_cast<std::size_t>((dy + r) * side + dx + r);
              const bool on_grid = o[0] + dx >= 0 && o[0] + dx < hf.nx && o[1] + dy >= 0 && o[1] + dy < hf.ny;
              if (on_grid) {
                ASSERT_EQ(grid[k], full[k]) << "observer " << o[0] << "," << o[1] << " target " << dx << "," << dy;
              } else if (grid[k] != kNoHorizon) {
                ++outside_set;
              }
            }
          }
          EXPECT_EQ(outside_set, 0);
        }
      }
    }
  }
}

TEST(HullKernel, VectorLevelsMatchTheScalarHorizon) {
  // The vectorised kernel and the scalar horizon implement the same recursion,
  // at the grid's corners and edges too (where the kernel leaves out the
  // targets outside the grid, and the scalar horizon computes them all), and
  // in a last chunk whose lanes run past the grid (45 posts: lanes 45..47).
  const Heightfield hf = fractal(45, 9);
  const int r = 12;
  VolumeGeometry g;
  g.nz = 100;
  g.z0_m = height_range(hf).min_m;
  g.dz_m = (height_range(hf).max_m - g.z0_m + 50.0) / (g.nz - 1);
  const PaddedTerrain t = pad_terrain(hf, g, r);
  const int exact_rings = 5;  // both the exact rings and the recursion
  const HullTable table(r, exact_rings, hf.spacing_m, 0.0, RangeShape::none, 0.0, t.stride);
  const LevelRowLayout layout(hf.nx, hf.ny, r);
  const LevelMap levels{static_cast<float>(g.z0_m), static_cast<float>(1.0 / g.dz_m), g.nz};
  std::vector<std::uint8_t> out(layout.bytes_per_observer_row(), 0);
  std::vector<float> ra(static_cast<std::size_t>(ring_size(r)) * kLanes);
  std::vector<float> rb(ra.size());
  int compared = 0, equal = 0;
  std::vector<float> horizon;
  const int chunks[][2] = {{16, 20}, {0, 0}, {32, 44}, {0, 40}, {32, 3}};
  for (const auto& at : chunks) {
    const int py = at[1];
    ObserverChunk chunk;
    chunk.px0 = at[0];
    chunk.py = py;
    for (int l = 0; l < kLanes; ++l) chunk.eye_m[l] = hf.at(std::min(chunk.px0 + l, hf.nx - 1), py) + 2.0f;
    hull_levels_chunk(table, t, layout, levels, RangeShape::none, chunk, ra.data(), rb.data(), out.data());
    for (int l = 0; l < kLanes && chunk.px0 + l < hf.nx; ++l) {
      const int px = chunk.px0 + l;
      observer_horizon(t, r, exact_rings, hf.spacing_m, 0.0, px, py, chunk.eye_m[l], horizon);
      for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
          const int x = px + dx, y = py + dy;
          if (x < 0 || y < 0 || x >= hf.nx || y >= hf.ny) continue;
          const double h = horizon[static_cast<std::size_t>((dy + r) * (2 * r + 1) + dx + r)];
          const double d = std::hypot(double(dx), double(dy)) * hf.spacing_m;
          const double hull = h <= kNoHorizon ? -1e30 : chunk.eye_m[l] + d * h;
          // clamped before the cast: no horizon is -1e30 m, far outside int
          const double level = std::floor((hull - g.z0_m) / g.dz_m) + 1;
          int expected = static_cast<int>(std::clamp(level, -1.0, static_cast<double>(g.nz)));
          expected = std::max(expected, t.ground_level[t.index(x, y)]);
          expected = std::clamp(expected, 0, g.nz);
          const int got = out[layout.offset(py, y, chunk.px0 / kLanes, dx - layout.first_dx(chunk.px0)) +
                              static_cast<std::size_t>(l)];
          ++compared;
          if (got == expected) ++equal;
          ASSERT_LE(std::abs(got - expected), 1) << "observer " << px << "," << py << " target " << x << "," << y;
        }
      }
    }
  }
  // Float against double rounding may move a hull across a level boundary rarely.
  EXPECT_GE(equal, compared - compared / 500) << equal << " of " << compared;
}

// The kernel runs at the CPU's vector width (AVX-512, AVX2 or SSE): every
// width computes each lane's levels with the same operations (the kernel is
// built without fused multiply-adds, -ffp-contract=off), so the levels are
// the same bytes at every width this CPU runs as at the baseline's (4 lanes;
// 16 in the sanitizer builds), for every range shape and for exact rings
// and the recursion alike. (This terrain does not happen to put a hull where
// one rounding step moves it across a level: the flag is what holds it.)
TEST(HullKernel, EveryVectorWidthGivesTheBaselinesLevels) {
  const Heightfield hf = fractal(56, 4);
  const int r = 14;
  VolumeGeometry g;
  g.nz = 90;
  g.z0_m = height_range(hf).min_m;
  g.dz_m = (height_range(hf).max_m - g.z0_m + 60.0) / (g.nz - 1);
  const PaddedTerrain t = pad_terrain(hf, g, r);
  const LevelRowLayout layout(hf.nx, hf.ny, r);
  const LevelMap levels{static_cast<float>(g.z0_m), static_cast<float>(1.0 / g.dz_m), g.nz};
  std::vector<float> ra(static_cast<std::size_t>(ring_size(r)) * kLanes), rb(ra.size());
  const int native_width = hull_kernel_width();
  EXPECT_TRUE(native_width == 4 || native_width == 8 || native_width == 16) << native_width;
  int baseline_width = 4;  // 16 in the sanitizer builds (4 is then no build)
  std::vector<int> widths_run;
  for (RangeShape shape : {RangeShape::none, RangeShape::cube, RangeShape::sphere}) {
    const HullTable table(r, 4, hf.spacing_m, 1.0 / 7.0, shape, r * hf.spacing_m * 0.8, t.stride);
    for (int py : {0, 23, hf.ny - 1}) {
      for (int px0 : {0, 16, 32, 48}) {
        ObserverChunk chunk;
        chunk.px0 = px0;
        chunk.py = py;
        for (int l = 0; l < kLanes; ++l) {
          chunk.eye_m[l] = hf.at(std::min(px0 + l, hf.nx - 1), py) + 2.0f + static_cast<float>(l);
          chunk.floor_level[l] = l % 3;
        }
        std::vector<std::uint8_t> baseline(layout.bytes_per_observer_row(), 0);
        if (!hull_levels_chunk_at_width(baseline_width, table, t, layout, levels, shape, chunk, ra.data(), rb.data(),
                                        baseline.data())) {
          baseline_width = 16;
          ASSERT_TRUE(hull_levels_chunk_at_width(16, table, t, layout, levels, shape, chunk, ra.data(), rb.data(),
                                                 baseline.data()));
        }
        for (int width : {16, 8}) {
          if (width == baseline_width) continue;
          std::vector<std::uint8_t> other(baseline.size(), 0);
          if (!hull_levels_chunk_at_width(width, table, t, layout, levels, shape, chunk, ra.data(), rb.data(),
                                          other.data())) {
            continue;
          }
          if (std::find(widths_run.begin(), widths_run.end(), width) == widths_run.end()) widths_run.push_back(width);
          ASSERT_EQ(other, baseline) << "width " << width << ", shape " << to_string(shape) << ", chunk at " << px0
                                     << "," << py;
        }
      }
    }
  }
  // the native width is among those compared (unless it is the baseline's)
  if (native_width != baseline_width) {
    EXPECT_NE(std::find(widths_run.begin(), widths_run.end(), native_width), widths_run.end()) << native_width;
  }
}

TEST(HullKernel, PaddingNeverBlocksAndGroundLevelsAreClamped) {
  const Heightfield hf = flat(8);
  VolumeGeometry g;
  g.nz = 5;
  g.z0_m = 50;
  g.dz_m = 20;
  const PaddedTerrain t = pad_terrain(hf, g, 4);
  EXPECT_EQ(t.ground_level[t.index(0, 0)], 3);   // ceil((100 - 50) / 20)
  EXPECT_EQ(t.ground_level[t.index(-1, 0)], 5);  // padding: never a target
  EXPECT_LT(t.height_m[t.index(-3, -3)], -1.0e5f);
}

}  // namespace
}  // namespace visvol::fields
