#include "fields/sampler.hpp"

#include <gtest/gtest.h>

#include "fields/dense_level.hpp"
#include "fields/visibility_builder.hpp"
#include "probe_points.hpp"
#include "reference_sampler.hpp"
#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

// A field whose voxels hold a known function, on a known terrain.
struct Fixture {
  Heightfield terrain = blank(6, 5, 10.0, 0.0f);
  DenseVolume field;
  Fixture() {
    field.geometry.nx = 6;
    field.geometry.ny = 5;
    field.geometry.nz = 4;
    field.geometry.spacing_m = 10.0;
    field.geometry.origin_x = terrain.origin_x;
    field.geometry.origin_y = terrain.origin_y;
    field.geometry.z0_m = 0.0;
    field.geometry.dz_m = 5.0;
    field.values.resize(field.geometry.voxel_count());
    // F = 0.01 i + 0.02 j + 0.1 k: linear, so trilinear sampling is exact.
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i)
          field.values[field.geometry.index(i, j, k)] =
              0.01f * static_cast<float>(i) + 0.02f * static_cast<float>(j) + 0.1f * static_cast<float>(k);
  }
};

TEST(Sampler, TrilinearIsExactForALinearField) {
  Fixture fx;
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  const double x = fx.terrain.x_of(2.25), y = fx.terrain.y_of(1.5), z = 7.5;
  EXPECT_NEAR(s.visibility(x, y, z), 0.01 * 2.25 + 0.02 * 1.5 + 0.1 * 1.5, 1e-6);
  // At a voxel centre it returns the voxel.
  EXPECT_NEAR(s.visibility(fx.terrain.x_of(4), fx.terrain.y_of(3), 10.0), fx.field.at(4, 3, 2), 1e-7);
}

TEST(Sampler, BelowTheGridIsZeroAboveIsTheTopLevel) {
  Fixture fx;
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  const double x = fx.terrain.x_of(1), y = fx.terrain.y_of(1);
  EXPECT_EQ(s.visibility(x, y, -1.0), 0.0);
  EXPECT_NEAR(s.visibility(x, y, 1000.0), fx.field.at(1, 1, 3), 1e-7);
}

TEST(Sampler, GradientIsPerMetreInWorldAxes) {
  Fixture fx;
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  const Eigen::Vector3d g = s.gradient(fx.terrain.x_of(2.5), fx.terrain.y_of(2.5), 8.0);
  EXPECT_NEAR(g.x(), 0.01 / 10.0, 1e-7);
  EXPECT_NEAR(g.y(), -0.02 / 10.0, 1e-7);  // j grows southward, world y northward
  EXPECT_NEAR(g.z(), 0.1 / 5.0, 1e-7);
}

TEST(Sampler, GradientIsZeroAtAndBelowTheTerrain) {
  Fixture fx;
  fx.terrain.at(2, 2) = 12.0f;
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  const double x = fx.terrain.x_of(2), y = fx.terrain.y_of(2);
  EXPECT_EQ(s.gradient(x, y, 12.0), Eigen::Vector3d::Zero());
  EXPECT_EQ(s.gradient(x, y, 3.0), Eigen::Vector3d::Zero());
  EXPECT_NE(s.gradient(x, y, 16.0), Eigen::Vector3d::Zero());
}

TEST(Sampler, VoxelGradientUsesBackwardDifferencesAboveTheTerrain) {
  Fixture fx;
  fx.field.values[fx.field.geometry.index(3, 2, 2)] += 0.05f;  // a bump
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  // Backward in x at the bump: (F(3) - F(2)) / 10; just east of it the
  // backward difference sees the bump fall away.
  EXPECT_NEAR(s.voxel_gradient(3, 2, 2).x(), (0.01 + 0.05) / 10.0, 1e-6);
  EXPECT_NEAR(s.voxel_gradient(4, 2, 2).x(), (0.01 - 0.05) / 10.0, 1e-6);
  // Level 0 sits on the ground (z = 0 is not above terrain 0): zero there.
  EXPECT_EQ(s.voxel_gradient(3, 2, 0), Eigen::Vector3d::Zero());
  // Level 1's backward z neighbour is on the ground: forward difference.
  EXPECT_NEAR(s.voxel_gradient(3, 2, 1).z(), (0.1 + 0.05) / 5.0, 1e-6);
}

TEST(Sampler, HeightIsBilinearAndClampedOutside) {
  Fixture fx;
  fx.terrain.at(1, 1) = 8.0f;
  const FieldSampler<DenseLevelView> s(DenseLevelView(fx.terrain, fx.field));
  EXPECT_NEAR(s.height(fx.terrain.x_of(1), fx.terrain.y_of(1)), 8.0, 1e-9);
  EXPECT_NEAR(s.height(fx.terrain.x_of(1.5), fx.terrain.y_of(1)), 4.0, 1e-9);
  EXPECT_NEAR(s.height(fx.terrain.x_of(-5), fx.terrain.y_of(-5)), 0.0, 1e-9);
}

TEST(Sampler, RealFieldGradientPointsUpInOpenAir) {
  // Over a hilly terrain F_p grows with height: grad_z >= 0 well above ground.
  const Heightfield hf = fractal(40, 2);
  FieldParams p;
  p.nz = 40;
  p.range_shape = RangeShape::none;
  const Result<DenseVolume> f = build_visibility_dense(hf, p);
  ASSERT_TRUE(f.ok());
  const FieldSampler<DenseLevelView> s(DenseLevelView(hf, *f));
  for (int j = 5; j < 35; j += 6)
    for (int i = 5; i < 35; i += 6) {
      const double z = hf.at(i, j) + 40.0;
      EXPECT_GE(s.gradient(hf.x_of(i), hf.y_of(j), z).z(), 0.0);
    }
}

// The sampler reads each column's posts and tiles once per query; the values
// must be exactly those of reading every voxel through the level.
void expect_same_tff(const TffSample& a, const TffSample& b, const Eigen::Vector3d& p) {
  EXPECT_EQ(a.dx_m, b.dx_m) << p.transpose();
  EXPECT_EQ(a.dy_m, b.dy_m) << p.transpose();
  EXPECT_EQ(a.dz_m, b.dz_m) << p.transpose();
  EXPECT_EQ(a.signed_distance_m, b.signed_distance_m) << p.transpose();
}

// A level that offers neither column() nor field(): the sampler reads it
// through voxel() and tff() alone.
struct PlainLevel {
  const DenseLevel* level;
  const VolumeGeometry& geometry() const { return level->geometry(); }
  float post(int i, int j) const { return level->post(i, j); }
  float voxel(int i, int j, int k) const { return level->voxel(i, j, k); }
  TffSample tff(int i, int j, int b) const { return level->tff(i, j, b); }
  const TffParams& tff_params() const { return level->tff_params(); }
};

template <class Level>
void expect_matches_reference(const Level& level, const DenseLevel& dense) {
  const FieldSampler<Level> s(level);
  const testing::ReferenceSampler<DenseLevel> ref(dense);
  const auto points = testing::probe_points(
      dense.geometry(), [&](double x, double y) { return ref.height(x, y); }, 4000, 17);
  int above_ground = 0;
  for (const Eigen::Vector3d& q : points) {
    const double x = q.x(), y = q.y(), z = q.z();
    ASSERT_EQ(s.height(x, y), ref.height(x, y)) << q.transpose();
    ASSERT_EQ(s.visibility(x, y, z), ref.visibility(x, y, z)) << q.transpose();
    const Eigen::Vector3d g = ref.gradient(x, y, z);
    ASSERT_EQ(s.gradient(x, y, z), g) << q.transpose();
    expect_same_tff(s.terrain_force(x, y, z), ref.terrain_force(x, y, z), q);
    // one call for all three, and for each part alone
    for (int parts = 0; parts < 4; ++parts) {
      const bool with_gradient = parts & 1, with_tff = parts & 2;
      const PointSample all = s.sample(x, y, z, with_gradient, with_tff);
      ASSERT_EQ(all.height_m, ref.height(x, y)) << q.transpose();
      ASSERT_EQ(all.gradient_per_m, with_gradient ? g : Eigen::Vector3d::Zero()) << q.transpose();
      expect_same_tff(all.tff, with_tff ? ref.terrain_force(x, y, z) : TffSample{}, q);
    }
    above_ground += g != Eigen::Vector3d::Zero();
  }
  EXPECT_GT(above_ground, 1000);  // the gradient was really exercised
}

TEST(Sampler, MatchesTheStraightforwardSamplerEverywhere) {
  const Heightfield hf = fractal(70, 5);
  FieldParams p;
  p.nz = 24;
  p.range_posts = 8;
  TffParams tp;
  tp.band_offset_m = 40;
  tp.band_levels = 8;
  const Result<std::vector<DenseLevel>> levels = build_dense_levels(hf, p, 2, tp);
  ASSERT_TRUE(levels.ok()) << levels.status().message();
  for (const DenseLevel& level : *levels) {
    expect_matches_reference(level, level);               // its dense volume's columns
    expect_matches_reference(PlainLevel{&level}, level);  // voxel() and tff() only
  }
}

}  // namespace
}  // namespace visvol::fields
