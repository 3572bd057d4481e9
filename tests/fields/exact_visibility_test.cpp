#include "fields/exact_visibility.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

TEST(ExactVisibility, FlatGroundSeesEverythingAboveIt) {
  const Heightfield hf = flat(20);
  EXPECT_TRUE(r3_visible(hf, 2, 2, 102, 17, 11, 100.0, 0.0));
  EXPECT_TRUE(r3_visible(hf, 2, 2, 100.5, 17, 11, 100.5, 0.0));
  // A sight line lying on the ground is not strictly above it.
  EXPECT_FALSE(r3_visible(hf, 2, 2, 100, 17, 11, 100, 0.0));
}

TEST(ExactVisibility, WallHidesTheFarSide) {
  const Heightfield hf = wall(20, 10, 30.0f);
  EXPECT_FALSE(r3_visible(hf, 2, 5, 102, 18, 5, 100, 0.0));
  EXPECT_TRUE(r3_visible(hf, 2, 5, 102, 18, 5, 200, 0.0));
  // The wall's top is 130 m midway: the line must pass above it.
  EXPECT_FALSE(r3_visible(hf, 0, 5, 130, 20 - 1, 5, 130, 0.0));
  EXPECT_TRUE(r3_visible(hf, 0, 5, 130.5, 19, 5, 130.5, 0.0));
}

// A target anywhere (a path point of another area, a forged coordinate):
// judged over the grid it crosses, never a read beyond it.
TEST(ExactVisibility, SightLinesLeavingTheGridAreJudgedOverIt) {
  const Heightfield hf = wall(20, 10, 30.0f);
  // far beyond the grid in both axes: only the grid's part can block
  EXPECT_TRUE(r3_visible(hf, 2, 5, 102, 2, -1e7, 1e9, 0.0));
  EXPECT_TRUE(r3_visible(hf, 2, 5, 102, 1e7, 5, 1e9, 0.0));
  // the wall still hides what lies straight behind it, however far
  EXPECT_FALSE(r3_visible(hf, 2, 5, 102, 1e7, 5, 102, 0.0));
  EXPECT_FALSE(r3_visible(hf, 2, 5, 102, 1e300, 5, 102, 0.0));
  // both ends outside, the line crossing the grid over the wall, then not
  EXPECT_FALSE(r3_visible(hf, -50, 5, 110, 70, 5, 110, 0.0));
  EXPECT_TRUE(r3_visible(hf, -50, 5, 140, 70, 5, 140, 0.0));
  EXPECT_TRUE(r3_visible(hf, -50, -60, 90, 70, -40, 90, 0.0));  // misses the grid: nothing in the way
  for (double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_FALSE(r3_visible(hf, 2, 5, 102, bad, 5, 102, 0.0));
    EXPECT_FALSE(r3_visible(hf, 2, 5, bad, 18, 5, 102, 0.0));
  }
}

TEST(ExactVisibility, InterpolatesAlongGridLines) {
  // Posts 0 and 10 m high on the crossed grid line x = 1; the sight line
  // crosses it halfway between them, where the terrain is 5 m.
  Heightfield hf = blank(3, 3, 1.0, 0.0f);
  hf.at(1, 0) = 0.0f;
  hf.at(1, 1) = 10.0f;
  EXPECT_TRUE(r3_visible(hf, 0, 0, 5.1, 2, 1, 5.1, 0.0));
  EXPECT_FALSE(r3_visible(hf, 0, 0, 4.9, 2, 1, 4.9, 0.0));
}

TEST(ExactVisibility, CurvatureHidesDistantLowTargets) {
  // 100 km apart over the sea: the drop at the far end is about 670 m.
  const Heightfield hf = blank(101, 3, 1000.0, 0.0f);
  EXPECT_TRUE(r3_visible(hf, 0, 1, 10, 100, 1, 10, 0.0));
  EXPECT_FALSE(r3_visible(hf, 0, 1, 10, 100, 1, 10, 0.85714));
  EXPECT_TRUE(r3_visible(hf, 0, 1, 10, 100, 1, 1000, 0.85714));
}

TEST(ExactVisibility, FieldValueCountsVisibleObserversByArea) {
  const Heightfield hf = wall(9, 4, 50.0f);
  const std::vector<float> area = area_factor(hf);
  FieldParams p;
  p.range_shape = RangeShape::none;
  p.eye_height_m = 0;
  // Above the wall's top everything is visible; just above the ground east of
  // the wall (column 4), the western observers are hidden: the value is the
  // eastern posts' share of the area, with or without the wall's own posts.
  double total = 0, east = 0, wall_posts = 0;
  for (int j = 0; j < hf.ny; ++j) {
    for (int i = 0; i < hf.nx; ++i) {
      const double a = area[static_cast<std::size_t>(j * hf.nx + i)];
      total += a;
      if (i > 4) east += a;
      if (i == 4) wall_posts += a;
    }
  }
  EXPECT_NEAR(exact_visibility(hf, area, p, 7, 4, 1000.0), 1.0, 1e-12);
  const double low = exact_visibility(hf, area, p, 7, 4, 100.5);
  EXPECT_GE(low, east / total - 1e-12);
  EXPECT_LE(low, (east + wall_posts) / total + 1e-12);
  EXPECT_EQ(exact_visibility(hf, area, p, 7, 4, 99.0), 0.0);  // below the ground
}

}  // namespace
}  // namespace visvol::fields
