#include "fields/heightfield.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "terrains.hpp"

namespace visvol::fields {
namespace {

using testing::blank;

TEST(Heightfield, ValidGridPasses) { EXPECT_TRUE(validate(blank(3, 2, 10.0), "dem").ok()); }

TEST(Heightfield, RejectsNaNPostNamingIt) {
  Heightfield hf = blank(4, 4, 10.0);
  hf.at(2, 3) = std::numeric_limits<float>::quiet_NaN();
  const Status st = validate(hf, "dem.tif");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find("dem.tif"), std::string::npos);
  EXPECT_NE(st.message().find("(2, 3)"), std::string::npos);
}

TEST(Heightfield, RejectsNodataLeftInHeights) {
  Heightfield hf = blank(4, 4, 10.0);
  hf.at(0, 1) = -32768.0f;
  const Status st = validate(hf, "dem");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("-32768"), std::string::npos);
}

TEST(Heightfield, RejectsEmptyAndSinglePostGrids) {
  Heightfield empty;
  EXPECT_FALSE(validate(empty, "dem").ok());
  const Status one = validate(blank(1, 1, 10.0), "dem");
  ASSERT_FALSE(one.ok());
  EXPECT_NE(one.message().find("1 x 1"), std::string::npos);
}

TEST(Heightfield, RejectsZeroNegativeAndNaNSpacing) {
  for (double s : {0.0, -30.0, std::nan("")}) {
    Heightfield hf = blank(4, 4, 10.0);
    hf.spacing_m = s;
    const Status st = validate(hf, "dem");
    ASSERT_FALSE(st.ok()) << s;
    EXPECT_NE(st.message().find("spacing"), std::string::npos);
  }
}

TEST(Heightfield, RejectsAbsurdSizesBeforeAllocating) {
  Heightfield hf;
  hf.nx = 1 << 20;
  hf.ny = 1 << 20;
  hf.spacing_m = 1;
  const Status st = validate(hf, "dem");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("1048576"), std::string::npos);
}

TEST(Heightfield, RejectsHeightCountMismatch) {
  Heightfield hf = blank(4, 4, 10.0);
  hf.height_m.pop_back();
  EXPECT_FALSE(validate(hf, "dem").ok());
}

TEST(Heightfield, AreaFactorIsOneOnFlatGround) {
  for (float a : area_factor(blank(5, 5, 10.0))) EXPECT_FLOAT_EQ(a, 1.0f);
}

TEST(Heightfield, AreaFactorOfAPlaneIsItsSlopeFactor) {
  // z = 0.3 x - 0.4 y (world y is north, so j grows southward: +0.4 per post south).
  Heightfield hf = blank(6, 5, 10.0, 0.0f);
  for (int j = 0; j < hf.ny; ++j)
    for (int i = 0; i < hf.nx; ++i) hf.at(i, j) = static_cast<float>(3.0 * i + 4.0 * j);
  const double expected = std::sqrt(1.0 + 0.3 * 0.3 + 0.4 * 0.4);
  for (float a : area_factor(hf)) EXPECT_NEAR(a, expected, 1e-6);
}

TEST(Heightfield, DownsampleAveragesBlocksAndShiftsOrigin) {
  Heightfield hf = blank(5, 4, 10.0, 0.0f);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i) hf.at(i, j) = static_cast<float>(i + 10 * j);
  const Heightfield c = downsample2(hf);
  EXPECT_EQ(c.nx, 2);  // the odd last column is dropped
  EXPECT_EQ(c.ny, 2);
  EXPECT_DOUBLE_EQ(c.spacing_m, 20.0);
  EXPECT_DOUBLE_EQ(c.origin_x, hf.origin_x + 5.0);
  EXPECT_DOUBLE_EQ(c.origin_y, hf.origin_y - 5.0);
  EXPECT_FLOAT_EQ(c.at(0, 0), (0 + 1 + 10 + 11) / 4.0f);
  EXPECT_FLOAT_EQ(c.at(1, 1), (22 + 23 + 32 + 33) / 4.0f);
  // The coarse post sits at the centre of its block.
  EXPECT_DOUBLE_EQ(c.x_of(1), 0.5 * (hf.x_of(2) + hf.x_of(3)));
}

TEST(Heightfield, BilinearHeightInterpolatesAndClamps) {
  Heightfield hf = blank(3, 3, 10.0, 0.0f);
  hf.at(1, 1) = 4.0f;
  EXPECT_DOUBLE_EQ(bilinear_height(hf, 1.0, 1.0), 4.0);
  EXPECT_DOUBLE_EQ(bilinear_height(hf, 0.5, 1.0), 2.0);
  EXPECT_DOUBLE_EQ(bilinear_height(hf, 0.5, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(bilinear_height(hf, -7.0, 1.0), 0.0);
}

TEST(Heightfield, WorldAndGridCoordinatesRoundTrip) {
  const Heightfield hf = blank(10, 10, 30.0);
  EXPECT_DOUBLE_EQ(hf.i_of(hf.x_of(3.25)), 3.25);
  EXPECT_DOUBLE_EQ(hf.j_of(hf.y_of(7.5)), 7.5);
  EXPECT_LT(hf.y_of(1), hf.y_of(0));  // row 1 is south of row 0
}

}  // namespace
}  // namespace visvol::fields
