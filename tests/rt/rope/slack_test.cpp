#include "rt/rope/slack.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace visvol::rt {
namespace {

// A 2 km x 2 km field, posts every 10 m, top at 500 m.
fields::VolumeGeometry field() {
  fields::VolumeGeometry g;
  g.nx = g.ny = 201;
  g.nz = 51;
  g.spacing_m = 10;
  g.origin_x = 0;
  g.origin_y = 2000;
  g.z0_m = 0;
  g.dz_m = 10;
  return g;
}

// Ground rising from 0 at x = 0 to 200 m at x = 2000 m.
double ramp_ground(double x, double) { return 0.1 * x; }

std::vector<Vec3> lay(const Vec3& a, const Vec3& b, int n, int half_waves, double length_m, double floor_m,
                      double* laid_m) {
  std::vector<Vec3> out(static_cast<std::size_t>(n) + 1);
  *laid_m = lay_with_slack([&](int i) { return Vec3(a + (double(i) / n) * (b - a)); }, n, half_waves, length_m, floor_m,
                           field(), ramp_ground, out.data());
  return out;
}

TEST(Slack, KeepsTheEndsAndReachesTheLength) {
  const Vec3 a(500, 1000, 300), b(1500, 1000, 400);
  const double straight = (b - a).norm();
  for (int waves : {1, 8}) {
    double laid = 0;
    const std::vector<Vec3> p = lay(a, b, 64, waves, 1.3 * straight, 30, &laid);
    EXPECT_EQ(p.front(), a);
    EXPECT_EQ(p.back(), b);
    EXPECT_NEAR(laid, 1.3 * straight, 1e-6 * straight) << waves << " half waves";
    EXPECT_NEAR(polyline_length_m(p.data(), 65), laid, 1e-9);
  }
}

TEST(Slack, BendsSidewaysNotUp) {
  // Far above the ground: a lifted rope would rise, a sideways one keeps its heights.
  const Vec3 a(500, 1000, 400), b(1500, 1000, 400);
  double laid = 0;
  const std::vector<Vec3> p = lay(a, b, 64, 1, 1.2 * (b - a).norm(), 30, &laid);
  double widest = 0;
  for (const Vec3& v : p) {
    EXPECT_DOUBLE_EQ(v.z(), 400.0);
    widest = std::max(widest, std::abs(v.y() - 1000));
  }
  EXPECT_GT(widest, 100.0);
}

TEST(Slack, StaysAboveTheFloorAndInsideTheField) {
  // Low ends near the south-east corner: the bend goes north-west, into the
  // field, and the interior keeps 30 m over the rising ground.
  const Vec3 a(1200, 40, 130), b(1900, 40, 200);
  double laid = 0;
  const std::vector<Vec3> p = lay(a, b, 64, 1, 1.5 * (b - a).norm(), 30, &laid);
  for (std::size_t i = 1; i + 1 < p.size(); ++i) {
    EXPECT_GE(p[i].z(), ramp_ground(p[i].x(), p[i].y()) + 30 - 1e-9) << i;
    EXPECT_GE(p[i].y(), 0.0);
    EXPECT_LE(p[i].y(), 2000.0);
    EXPECT_GE(p[i].x(), 0.0);
    EXPECT_LE(p[i].x(), 2000.0);
  }
  EXPECT_GT(p[32].y(), 100.0);  // bent towards the room
}

TEST(Slack, NoSlackAskedIsTheStraightPath) {
  const Vec3 a(500, 1000, 300), b(1500, 1200, 300);
  double laid = 0;
  const std::vector<Vec3> p = lay(a, b, 16, 1, 10.0, 0, &laid);
  EXPECT_NEAR(laid, (b - a).norm(), 1e-9);
  EXPECT_NEAR((p[8] - 0.5 * (a + b)).norm(), 0.0, 1e-9);
}

}  // namespace
}  // namespace visvol::rt
