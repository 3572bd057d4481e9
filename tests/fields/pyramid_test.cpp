#include "fields/pyramid.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

TEST(Pyramid, LevelsHalveTheGridAndShareTheVerticalGrid) {
  const Heightfield hf = fractal(64, 3);
  FieldParams p;
  p.nz = 32;
  p.range_posts = 8;
  const Result<std::vector<LodLevel>> levels = build_pyramid_dense(hf, p, 3);
  ASSERT_TRUE(levels.ok()) << levels.status().message();
  ASSERT_EQ(levels->size(), 3u);
  const VolumeGeometry& g0 = (*levels)[0].field.geometry;
  for (std::size_t l = 0; l < 3; ++l) {
    const VolumeGeometry& g = (*levels)[l].field.geometry;
    EXPECT_EQ(g.nx, 64 >> l);
    EXPECT_DOUBLE_EQ(g.spacing_m, hf.spacing_m * (1 << l));
    EXPECT_DOUBLE_EQ(g.z0_m, g0.z0_m);
    EXPECT_DOUBLE_EQ(g.dz_m, g0.dz_m);
    EXPECT_EQ(g.nz, 32);
  }
}

TEST(Pyramid, CoarseLevelIsTheFieldOfTheDownsampledTerrain) {
  const Heightfield hf = fractal(48, 5);
  FieldParams p;
  p.nz = 24;
  p.range_posts = 6;
  const Result<std::vector<LodLevel>> levels = build_pyramid_dense(hf, p, 2);
  ASSERT_TRUE(levels.ok());
  FieldParams direct = p;
  const VolumeGeometry g0 = volume_geometry(hf, p);
  direct.vertical = VerticalGrid{g0.z0_m, g0.dz_m};
  const Result<DenseVolume> coarse = build_visibility_dense(downsample2(hf), direct);
  ASSERT_TRUE(coarse.ok());
  const DenseVolume& got = (*levels)[1].field;
  ASSERT_EQ(got.values.size(), coarse->values.size());
  EXPECT_EQ(0, std::memcmp(got.values.data(), coarse->values.data(), got.values.size() * sizeof(float)));
}

TEST(Pyramid, RefusesTooManyLevelsNamingTheLimit) {
  const Heightfield hf = flat(20);
  const Result<std::vector<LodInput>> in = lod_inputs(hf, FieldParams{}, 4);
  ASSERT_FALSE(in.ok());
  EXPECT_NE(in.status().message().find("at most 3 levels"), std::string::npos) << in.status().message();
}

TEST(Pyramid, WeightsAreAveragedPerLevel) {
  const Heightfield hf = flat(8);
  FieldParams p;
  p.weights.assign(hf.size(), 0.0f);
  for (int j = 0; j < 8; ++j) p.weights[static_cast<std::size_t>(j * 8)] = 1.0f;  // column 0
  const Result<std::vector<LodInput>> in = lod_inputs(hf, p, 2);
  ASSERT_TRUE(in.ok());
  const std::vector<float>& w1 = (*in)[1].params.weights;
  ASSERT_EQ(w1.size(), 16u);
  EXPECT_FLOAT_EQ(w1[0], 0.5f);
  EXPECT_FLOAT_EQ(w1[1], 0.0f);
}

}  // namespace
}  // namespace visvol::fields
