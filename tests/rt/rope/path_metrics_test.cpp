#include "rt/rope/path_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace visvol::rt {
namespace {

// F_p = z / 1000 over flat ground at height 0.
struct Linear final : PathField {
  double visibility(const Vec3& p) const override { return p.z() / 1000.0; }
  double terrain_height_m(double, double) const override { return 0.0; }
};

TEST(PathMetrics, FcIsTheMeanAlongTheArcLength) {
  const Linear f;
  // 100 m at 100 m height, then 300 m at 300 m: arc-length mean = 0.25.
  const std::vector<Vec3> path = {{0, 0, 100}, {100, 0, 100}, {100, 0, 300}, {400, 0, 300}};
  // the vertical part (200 m) is at mean 0.2: (100*0.1 + 200*0.2 + 300*0.3) / 600
  const double expected = (100 * 0.1 + 200 * 0.2 + 300 * 0.3) / 600.0;
  EXPECT_NEAR(path_fc(path.data(), 4, f, 6001), expected, 1e-4);
  // A longer path at the same F_p is not worth more.
  const std::vector<Vec3> short_path = {{0, 0, 100}, {10, 0, 100}};
  const std::vector<Vec3> long_path = {{0, 0, 100}, {1000, 0, 100}};
  EXPECT_NEAR(path_fc(short_path.data(), 2, f, 64), path_fc(long_path.data(), 2, f, 64), 1e-12);
}

TEST(PathMetrics, ImportanceWeightsParts) {
  const Linear f;
  const std::vector<Vec3> path = {{0, 0, 0}, {1000, 0, 1000}};
  const double first_half_only = path_fc(path.data(), 2, f, 10001, [](double t) { return t < 0.5 ? 2.0 : 0.0; });
  EXPECT_NEAR(first_half_only, 0.25, 1e-3);  // 2 x the mean over the first half (0.125) x 1
}

TEST(PathMetrics, LengthClearanceAnglesAndTurnRadius) {
  const Linear f;
  // a climb of 45 degrees, then level, then a 30 degree descent
  std::vector<Vec3> path = {{0, 0, 50}, {100, 0, 150}, {200, 0, 150}, {200 + 100 * std::sqrt(3.0), 0, 50}};
  PathMetrics m = path_metrics(path.data(), 4, f, 256, 1.0);
  EXPECT_NEAR(m.length_m, 100 * std::sqrt(2.0) + 100 + 200, 1e-9);
  EXPECT_NEAR(m.min_clearance_m, 50.0, 1e-9);
  EXPECT_NEAR(m.max_climb_deg, 45.0, 1e-9);
  EXPECT_NEAR(m.max_descent_deg, 30.0, 1e-9);
  // vertices on a circle of radius 500, 0.1 rad apart: fillets that may not
  // overlap fit a radius of 500 cos(0.05) (turn_radii_m), just inside the circle
  std::vector<Vec3> arc;
  for (int i = 0; i <= 12; ++i) {
    const double a = i * 0.1;
    arc.push_back({500 * std::cos(a), 500 * std::sin(a), 100});
  }
  m = path_metrics(arc.data(), static_cast<int>(arc.size()), f, 64, 1.0);
  EXPECT_NEAR(m.min_turn_radius_m, 500.0 * std::cos(0.05), 1e-6);
  // a straight path has no finite turn radius
  const std::vector<Vec3> line = {{0, 0, 10}, {1, 0, 10}, {2, 0, 10}};
  m = path_metrics(line.data(), 3, f, 16, 1.0);
  EXPECT_TRUE(std::isinf(m.min_turn_radius_m));
}

}  // namespace
}  // namespace visvol::rt
