// The field's forces as property tests over random fields (flat, rolling,
// steep, with a cliff; 5 to 90 m posts) and hostile points: whatever the
// terrain and whatever the query (outside the grid, NaN, infinite, 1e300 m),
// forces, F_p and heights are finite and within the field's values, and a
// rope laid and run on such a field never holds a non-finite position.
#include "rt/rope/field_forces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "../../fields/terrains.hpp"
#include "fields/dense_level.hpp"
#include "rt/rope/planner.hpp"
#include "rt/rope/slack.hpp"

namespace visvol::rt {
namespace {

using fields::DenseLevel;

struct RandomField {
  fields::Heightfield terrain;
  std::vector<DenseLevel> levels;  // one
  std::string what;
  const DenseLevel& level() const { return levels.front(); }
};

// One random field: 24 x 24 posts, a relief from flat to steep, sometimes a
// 300 m cliff along a column.
RandomField random_field(std::mt19937& rng) {
  const double spacings[] = {5.0, 30.0, 90.0};
  const double reliefs[] = {0.0, 60.0, 900.0};
  const double spacing = spacings[rng() % 3], relief = reliefs[rng() % 3];
  const std::uint32_t seed = static_cast<std::uint32_t>(rng());
  fields::Heightfield hf = fields::testing::fractal(24, seed, spacing, relief);
  const bool cliff = rng() % 3 == 0;
  if (cliff) {
    for (int j = 0; j < hf.ny; ++j)
      for (int i = 12; i < hf.nx; ++i) hf.at(i, j) += 300.0f;
  }
  fields::FieldParams fp;
  fp.nz = 16;
  fp.ceiling_m = 200;
  fp.range_shape = fields::RangeShape::cube;
  fp.range_posts = 8;
  fields::TffParams tp;
  tp.band_offset_m = 40;
  tp.band_levels = 8;
  auto levels = fields::build_dense_levels(hf, fp, 1, tp);
  std::string what = "spacing " + std::to_string(spacing) + " m, relief " + std::to_string(relief) + " m" +
                     (cliff ? ", a cliff" : "") + ", seed " + std::to_string(seed);
  if (!levels.ok()) return {std::move(hf), {}, what + ": " + levels.status().message()};
  return {std::move(hf), std::move(*levels), std::move(what)};
}

// Points a command, a pack or a diverging rope could ask about.
std::vector<Vec3> hostile_points(const fields::VolumeGeometry& g, std::mt19937& rng) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const double x0 = g.origin_x, y0 = g.origin_y, w = (g.nx - 1) * g.spacing_m, top = g.z0_m + g.nz * g.dz_m;
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  std::vector<Vec3> p;
  for (int n = 0; n < 200; ++n) p.emplace_back(x0 + u(rng) * w, y0 - u(rng) * w, g.z0_m + u(rng) * (top - g.z0_m));
  for (double bad : {nan, inf, -inf, 1e300, -1e300, 1e-300}) {
    p.emplace_back(bad, y0 - 0.5 * w, 0.5 * top);
    p.emplace_back(x0 + 0.5 * w, bad, 0.5 * top);
    p.emplace_back(x0 + 0.5 * w, y0 - 0.5 * w, bad);
    p.emplace_back(bad, bad, bad);
  }
  return p;
}

TEST(FieldForces, AnyQueryOnAnyFieldIsFiniteAndWithinTheField) {
  std::mt19937 rng(20261126);
  for (int trial = 0; trial < 8; ++trial) {
    const RandomField f = random_field(rng);
    ASSERT_EQ(f.levels.size(), 1u) << f.what;
    ForceGains gains;
    gains.k1_visibility = rng() % 2 ? -1.0 : 1.0;
    gains.max_agl_m = rng() % 2 ? 150.0 : std::numeric_limits<double>::infinity();
    const FieldForces<DenseLevel> forces(f.level(), gains);
    // each push saturates: visibility at kSaturation reference accelerations,
    // the clearance, ceiling and containment at a few times that
    const double most = 100.0 * FieldForces<DenseLevel>::kSaturation * forces.reference_acceleration();
    float lo = f.terrain.height_m[0], hi = lo;
    for (float h : f.terrain.height_m) lo = std::min(lo, h), hi = std::max(hi, h);
    for (const Vec3& p : hostile_points(f.level().geometry(), rng)) {
      const Vec3 a = forces.acceleration(p);
      ASSERT_TRUE(a.allFinite() && a.norm() <= most) << f.what << " at (" << p.transpose() << "): " << a.transpose();
      const double v = forces.visibility(p);
      ASSERT_TRUE(v >= 0.0 && v <= 1.0) << f.what << " at (" << p.transpose() << "): F_p " << v;
      const double h = forces.terrain_height_m(p.x(), p.y());
      ASSERT_TRUE(h >= lo - 1e-3 && h <= hi + 1e-3) << f.what << " at (" << p.transpose() << "): height " << h;
    }
  }
}

TEST(FieldForces, RopesOnRandomFieldsStayFinite) {
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int ran = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const RandomField f = random_field(rng);
    ASSERT_EQ(f.levels.size(), 1u) << f.what;
    const fields::VolumeGeometry& g = f.level().geometry();
    ForceGains gains;
    gains.k1_visibility = rng() % 2 ? -1.0 : 1.0;
    gains.clearance_m = 10;
    const FieldForces<DenseLevel> forces(f.level(), gains);
    // ends anywhere over the grid, from just above the ground to the field's top
    auto end = [&] {
      const double x = g.origin_x + u(rng) * (g.nx - 1) * g.spacing_m;
      const double y = g.origin_y - u(rng) * (g.ny - 1) * g.spacing_m;
      const double ground = forces.terrain_height_m(x, y);
      return Vec3(x, y, ground + 1.0 + u(rng) * (g.z0_m + g.nz * g.dz_m - ground));
    };
    const Vec3 from = end(), to = end();
    const int segments = 32;
    if ((to - from).norm() < segments * kMinSegmentM) continue;
    const RopeModel model = trial % 2 ? RopeModel::spring : RopeModel::articulated;
    const double accel = forces.reference_acceleration();
    const double length = 1.3 * (to - from).norm();
    const RopeParams p = scaled_rope_params(model, segments, length / segments, 1.0, accel);
    const double dt = std::min(0.004, std::max(stable_step_s(p, accel, 2.0), kMinPlanStep_s));
    auto made = make_rope(p);
    ASSERT_TRUE(made.ok()) << made.status().message();
    Rope& rope = **made;
    const std::vector<Vec3> line = with_slack({from, to}, length);
    ASSERT_TRUE(rope.reset(line.data(), static_cast<int>(line.size()), segments).ok()) << f.what;
    RopeEnds ends;
    ends.start_m = from;
    ends.end_m = to;
    rope.set_ends(ends);
    ++ran;
    for (int t = 0; t < 1000; ++t) {
      rope.step(dt, forces);
      if (t % 50 != 49) continue;
      for (int i = 0; i <= rope.segments(); ++i) {
        ASSERT_TRUE(rope.vertices()[i].allFinite()) << to_string(model) << " on " << f.what << ", step " << t;
      }
    }
  }
  EXPECT_GE(ran, 4) << "too few random ends were far enough apart to lay a rope";
}

}  // namespace
}  // namespace visvol::rt

namespace visvol::rt {
namespace {

// The field's top is a ceiling whatever the gains say: above it F_p is not
// known. With no max-agl and no max-altitude, a point over the top is pushed
// down and one well under it is not (a console rope flew over a low pack's
// top on 226 of its 319 vertices).
TEST(FieldForces, TheFieldsTopIsACeiling) {
  std::mt19937 rng(5);
  RandomField f = random_field(rng);
  ASSERT_FALSE(f.levels.empty()) << f.what;
  ForceGains gains;
  gains.k1_visibility = 0;
  gains.k2_terrain = 0;
  gains.clearance_m = 0;
  ASSERT_FALSE(std::isfinite(gains.max_agl_m));
  ASSERT_FALSE(std::isfinite(gains.max_altitude_m));
  const FieldForces<DenseLevel> forces(f.level(), gains);
  const fields::VolumeGeometry& g = f.level().geometry();
  const double x = g.origin_x + 0.5 * (g.nx - 1) * g.spacing_m, y = g.origin_y - 0.5 * (g.ny - 1) * g.spacing_m;
  EXPECT_LT(forces.acceleration(Vec3(x, y, g.top_m() + 5)).z(), 0.0) << f.what;
  const double ground = forces.terrain_height_m(x, y);
  EXPECT_EQ(forces.acceleration(Vec3(x, y, 0.5 * (ground + g.top_m()))).z(), 0.0) << f.what;
}

}  // namespace
}  // namespace visvol::rt
