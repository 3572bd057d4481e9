// The articulated rope's joint solve forms its coupling blocks from cross
// products instead of full products with cross-product matrices: the values
// must be exactly those of the full products.
#include "rt/rope/articulated_rope.hpp"

#include <gtest/gtest.h>

#include <random>

namespace visvol::rt {
namespace {

// The cross-product matrix of r: [r]x v = r x v.
Eigen::Matrix3d cross_matrix(const Vec3& r) {
  Eigen::Matrix3d m;
  m << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return m;
}

// Vectors and matrices of mixed signs and magnitudes, with exact zeros and
// ones among their entries (where a skipped zero term could show).
struct Random {
  std::mt19937 rng{11};
  double value() {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    switch (rng() % 8) {
      case 0: return 0.0;
      case 1: return 1.0;
      case 2: return u(rng) * 1e-9;
      case 3: return u(rng) * 1e6;
      default: return u(rng) * 10.0;
    }
  }
  Vec3 vector() { return {value(), value(), value()}; }
  Eigen::Matrix3d matrix() {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m(i) = value();
    return m;
  }
  // an inverse inertia in world axes: symmetric positive definite
  Eigen::Matrix3d inverse_inertia() {
    const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::Vector4d::Random()).normalized();
    const Eigen::Matrix3d r = q.toRotationMatrix();
    const Vec3 inv = Vec3(1.0 / 40.0, 1.0 / 40.0, 1.0 / 0.5) * (1 + 0.1 * std::abs(value()));
    return r * inv.asDiagonal() * r.transpose();
  }
};

TEST(ArticulatedRope, CrossProductFormsAreTheFullProducts) {
  Random random;
  for (int n = 0; n < 20000; ++n) {
    const Vec3 r = random.vector();
    const Eigen::Matrix3d m = random.matrix();
    const Eigen::Matrix3d left = cross_matrix(r) * m, right = m * cross_matrix(r);
    ASSERT_EQ(detail::cross_times(r, m), left) << "r " << r.transpose() << "\nm\n" << m;
    ASSERT_EQ(detail::times_cross(m, r), right) << "r " << r.transpose() << "\nm\n" << m;
  }
}

TEST(ArticulatedRope, JointCouplingsAreTheThreeFactorProducts) {
  // [r1]x I^-1 [r2]x for two attachment points of one capsule, as the joint
  // solve forms it: the left half once, then the right factor.
  Random random;
  for (int n = 0; n < 20000; ++n) {
    const Vec3 r1 = random.vector(), r2 = n % 3 == 0 ? Vec3(-r1) : random.vector();
    const Eigen::Matrix3d ii = random.inverse_inertia();
    const Eigen::Matrix3d full = cross_matrix(r1) * ii * cross_matrix(r2);
    ASSERT_EQ(detail::times_cross(detail::cross_times(r1, ii), r2), full)
        << "r1 " << r1.transpose() << " r2 " << r2.transpose();
  }
}

}  // namespace
}  // namespace visvol::rt

namespace visvol::rt {
namespace {

// The small-angle series agrees with the angle-axis form (sin and cos) to
// rounding, on both sides of the switch between them, and stays a unit quaternion.
TEST(ArticulatedRope, ExponentialMapSeriesMatchesAngleAxis) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (double angle : {1e-9, 1e-6, 1e-4, 9.99e-4, 1.001e-3, 1e-2, 1.0}) {
    for (int n = 0; n < 50; ++n) {
      const Vec3 axis = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
      const Eigen::Quaterniond q = detail::exp_map(angle * axis);
      const Eigen::Quaterniond ref(Eigen::AngleAxisd(angle, axis));
      ASSERT_NEAR(q.w(), ref.w(), 1e-15) << angle;
      ASSERT_LT((q.vec() - ref.vec()).norm(), 1e-15) << angle;
      ASSERT_NEAR(q.norm(), 1.0, 1e-15) << angle;
    }
  }
  EXPECT_EQ(detail::exp_map(Vec3::Zero()).coeffs(), Eigen::Quaterniond::Identity().coeffs());
}

// A capsule laid along a segment: its body z turned onto the segment by the
// shortest rotation (the axis across both), a unit quaternion, for any
// direction and length, straight down (a half turn) and straight up included.
TEST(ArticulatedRope, BodyZTurnsOntoTheSegmentTheShortestWay) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3> dirs = {Vec3::UnitZ(),        -Vec3::UnitZ(),    Vec3::UnitX() * 1e-9, Vec3(1e-13, 0, -1),
                            Vec3(1.2e-12, 0, -1), Vec3(0, 1e-6, -1), Vec3(1e-200, 0, -1),  Vec3(0, 3, -4)};
  for (int n = 0; n < 200; ++n) dirs.push_back(Vec3(unit(rng), unit(rng), unit(rng)) * std::pow(10.0, 4 * unit(rng)));
  for (const Vec3& dir : dirs) {
    const Eigen::Quaterniond q = detail::from_body_z(dir);
    ASSERT_NEAR(q.norm(), 1.0, 2e-15) << dir.transpose();
    ASSERT_LT((q * Vec3::UnitZ() - dir.normalized()).norm(), 1e-12) << dir.transpose();
    const Vec3 axis = q.vec();
    ASSERT_LT(std::abs(axis.z()), 1e-15) << dir.transpose();                    // across z
    ASSERT_LT(std::abs(axis.dot(dir.normalized())), 1e-12) << dir.transpose();  // and across dir
    ASSERT_GE(q.w(), 0.0) << dir.transpose();                                   // at most a half turn
  }
  EXPECT_EQ(detail::from_body_z(Vec3(0, 0, 5)).coeffs(), Eigen::Quaterniond::Identity().coeffs());
}

}  // namespace
}  // namespace visvol::rt
