#include "fields/terrain_force.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "fields/worker_pool.hpp"
#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

// Height of the triangulated terrain (north-west to south-east diagonals) at
// world (x, y).
double triangulated_height(const Heightfield& hf, double x, double y) {
  const double u = hf.i_of(x), v = hf.j_of(y);
  const int i = std::clamp(static_cast<int>(std::floor(u)), 0, hf.nx - 2);
  const int j = std::clamp(static_cast<int>(std::floor(v)), 0, hf.ny - 2);
  const double fu = u - i, fv = v - j;
  const double a = hf.at(i, j), b = hf.at(i + 1, j), c = hf.at(i + 1, j + 1), d = hf.at(i, j + 1);
  // Triangle abc holds fu >= fv; triangle acd the rest.
  return fu >= fv ? a + fu * (b - a) + fv * (c - b) : a + fv * (d - a) + fu * (c - d);
}

TEST(TerrainForce, NearestPointOverFlatGroundIsStraightBelow) {
  const Heightfield hf = flat(12, 10.0);
  const Eigen::Vector3d q{hf.x_of(5.3), hf.y_of(6.7), 142.0};
  const NearestTerrainPoint n = nearest_terrain_point(hf, q, 1e9);
  EXPECT_NEAR(n.distance_m, 42.0, 1e-9);
  EXPECT_NEAR(n.point_m.x(), q.x(), 1e-9);
  EXPECT_NEAR(n.point_m.y(), q.y(), 1e-9);
  EXPECT_NEAR(n.point_m.z(), 100.0, 1e-9);
}

TEST(TerrainForce, NearestPointLiesOnTheTriangulatedSurface) {
  const Heightfield hf = fractal(24, 7, 30.0, 200.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(2.0, 21.0);
  for (int n = 0; n < 300; ++n) {
    const double x = hf.x_of(u(rng)), y = hf.y_of(u(rng));
    const Eigen::Vector3d q{x, y, triangulated_height(hf, x, y) + (n % 2 ? 60.0 : -40.0)};
    const NearestTerrainPoint p = nearest_terrain_point(hf, q, 1e9);
    EXPECT_NEAR(p.point_m.z(), triangulated_height(hf, p.point_m.x(), p.point_m.y()), 1e-6);
    EXPECT_NEAR(p.distance_m, (p.point_m - q).norm(), 1e-9);
  }
}

TEST(TerrainForce, BandMatchesBruteForceNearestPoints) {
  // The band search is bounded; a search over the whole grid must agree: at
  // the CPU's width and at the baseline's, with spare lanes in the last
  // vector of a column (11 samples).
  const Heightfield hf = fractal(20, 11, 30.0, 300.0);
  TffParams p;
  p.band_offset_m = 80.0;
  p.band_levels = 11;
  for (const bool baseline : {false, true}) {
    SCOPED_TRACE(baseline ? "baseline" : "the CPU's width");
    std::vector<TffSample> band(static_cast<std::size_t>(hf.ny) * static_cast<std::size_t>(p.band_levels) *
                                static_cast<std::size_t>(hf.nx));
    if (baseline) {
      terrain_force_rows_baseline(hf, p, 0, hf.ny, band.data());
    } else {
      terrain_force_rows(hf, p, 0, hf.ny, band.data(), nullptr);
    }
    for (int j = 0; j < hf.ny; ++j) {
      for (int b = 0; b < p.band_levels; ++b) {
        for (int i = 0; i < hf.nx; ++i) {
          const TffSample& s = band[static_cast<std::size_t>((j * p.band_levels + b) * hf.nx + i)];
          const double z = hf.at(i, j) - p.band_offset_m + b * p.step_m();
          const Eigen::Vector3d q{hf.x_of(i), hf.y_of(j), z};
          const NearestTerrainPoint brute = nearest_terrain_point(hf, q, 1e9);
          ASSERT_NEAR(std::fabs(s.signed_distance_m), brute.distance_m, 1e-3) << i << "," << j << "," << b;
          EXPECT_EQ(s.signed_distance_m < 0, z < hf.at(i, j));
          // Outward displacement: q minus the nearest point above, the reverse inside.
          const Eigen::Vector3d e{s.dx_m, s.dy_m, s.dz_m};
          EXPECT_NEAR(e.norm(), brute.distance_m, 1e-3);
          const Eigen::Vector3d surface = s.signed_distance_m >= 0 ? Eigen::Vector3d(q - e) : Eigen::Vector3d(q + e);
          EXPECT_NEAR(surface.z(), triangulated_height(hf, surface.x(), surface.y()), 1e-3);
        }
      }
    }
  }
}

TEST(TerrainForce, InsideTheTerrainPointsOut) {
  const Heightfield hf = flat(10, 10.0);
  TffParams p;
  p.band_offset_m = 50.0;
  p.band_levels = 10;
  std::vector<TffSample> band(static_cast<std::size_t>(hf.ny) * static_cast<std::size_t>(p.band_levels) *
                              static_cast<std::size_t>(hf.nx));
  terrain_force_rows(hf, p, 0, hf.ny, band.data(), nullptr);
  const TffSample& deep = band[static_cast<std::size_t>((5 * p.band_levels + 0) * hf.nx + 5)];
  EXPECT_NEAR(deep.signed_distance_m, -50.0, 1e-4);
  EXPECT_NEAR(deep.dz_m, 50.0, 1e-4);  // up, out of the ground
  const TffSample& high = band[static_cast<std::size_t>((5 * p.band_levels + 9) * hf.nx + 5)];
  EXPECT_NEAR(high.signed_distance_m, 50.0, 1e-4);
  EXPECT_NEAR(high.dz_m, 50.0, 1e-4);  // up, away from the ground
}

TEST(TerrainForce, ThreadedRowsEqualSerialRows) {
  const Heightfield hf = fractal(33, 2);
  TffParams p;
  std::vector<TffSample> a(static_cast<std::size_t>(hf.ny) * static_cast<std::size_t>(p.band_levels) *
                           static_cast<std::size_t>(hf.nx)),
      b(a.size());
  terrain_force_rows(hf, p, 0, hf.ny, a.data(), nullptr);
  WorkerPool pool(3);
  terrain_force_rows(hf, p, 0, hf.ny, b.data(), &pool);
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(TffSample)));
}

TEST(TerrainForce, EveryWidthFindsTheSameDistances) {
  // The CPU's lanes (4 with AVX2 or AVX-512) against the baseline's 2, with
  // spare lanes in the last vector of both (11 samples a column): the same
  // nearest distances to the bit, the same points but where two are equally near.
  const Heightfield hf = fractal(26, 5, 30.0, 250.0);
  TffParams p;
  p.band_offset_m = 90.0;
  p.band_levels = 11;
  std::vector<TffSample> cpu(static_cast<std::size_t>(hf.ny) * static_cast<std::size_t>(p.band_levels) *
                             static_cast<std::size_t>(hf.nx)),
      base(cpu.size());
  terrain_force_rows(hf, p, 0, hf.ny, cpu.data(), nullptr);
  terrain_force_rows_baseline(hf, p, 0, hf.ny, base.data());
  for (std::size_t n = 0; n < cpu.size(); ++n) {
    ASSERT_EQ(cpu[n].signed_distance_m, base[n].signed_distance_m) << "sample " << n;
    EXPECT_NEAR(cpu[n].dx_m, base[n].dx_m, 1e-3);
    EXPECT_NEAR(cpu[n].dy_m, base[n].dy_m, 1e-3);
    EXPECT_NEAR(cpu[n].dz_m, base[n].dz_m, 1e-3);
  }
}

TEST(TerrainForce, RejectsBadParameters) {
  EXPECT_FALSE(validate(TffParams{0.0, 32}).ok());
  EXPECT_FALSE(validate(TffParams{0.5, 32}).ok());  // under a metre: no band to push the rope off the ground
  EXPECT_FALSE(validate(TffParams{std::nan(""), 32}).ok());
  EXPECT_TRUE(validate(TffParams{1.0, 32}).ok());
  EXPECT_FALSE(validate(TffParams{500.0, 32}).ok());
  EXPECT_FALSE(validate(TffParams{100.0, 1}).ok());
  EXPECT_TRUE(validate(TffParams{100.0, 32}).ok());
}

// The band's reach in posts bounds the nearest-point search (it meets every
// cell within it): 100 m over 0.05 m posts is 2001 posts, refused naming
// what to change (it had built a 9.5 GB table and run for hours); over 0.5 m
// posts it is 201.
TEST(TerrainForce, ABandOfTooManyPostsIsRefused) {
  EXPECT_EQ(tff_reach_posts(TffParams{100.0, 24}, 0.5), 201);
  EXPECT_TRUE(validate(TffParams{100.0, 24}, 0.5).ok());
  const Status fine = validate(TffParams{100.0, 24}, 0.05);
  EXPECT_EQ(fine.code(), Errc::invalid_argument);
  EXPECT_NE(fine.message().find("2001 posts"), std::string::npos) << fine.message();
  EXPECT_NE(fine.message().find("--tff-offset"), std::string::npos) << fine.message();
  EXPECT_NE(fine.message().find("--spacing"), std::string::npos) << fine.message();
  EXPECT_FALSE(validate(TffParams{100.0, 24}, 0.0).ok());
  EXPECT_FALSE(validate(TffParams{100.0, 24}, std::nan("")).ok());
  EXPECT_FALSE(validate(TffParams{0.5, 24}, 30.0).ok());  // and what validate(params) refuses
}

}  // namespace
}  // namespace visvol::fields
