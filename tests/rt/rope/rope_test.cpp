#include "rt/rope/rope.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "rt/rope/articulated_rope.hpp"
#include "rt/rope/planner.hpp"
#include "rt/rope/spring_mass_rope.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::rt {
namespace {

// A field that pushes each point towards a wavy surface, with a swirl: strong,
// varying along the rope, and not a potential (so it can pump energy if the
// integrator lets it).
struct Wavy final : RopeEnvironment {
  double strength = 800.0;
  Vec3 acceleration(const Vec3& p) const override {
    const double target = 120.0 * std::sin(p.x() / 90.0) + 60.0 * std::cos(p.y() / 70.0);
    return {0.3 * strength * std::sin(p.z() / 50.0), 0.2 * strength * std::cos(p.x() / 40.0),
            strength * std::tanh((target - p.z()) / 40.0)};
  }
};
struct Uniform final : RopeEnvironment {
  Vec3 a = Vec3::Zero();
  Vec3 acceleration(const Vec3&) const override { return a; }
};

std::unique_ptr<Rope> laid_rope(RopeModel model, int segments, double slack, Vec3 from = {0, 0, 0},
                                Vec3 to = {1000, 200, 0}) {
  const double straight = (to - from).norm();
  RopeParams p = scaled_rope_params(model, segments, (1 + slack) * straight / segments, 1.0, 1000.0);
  p.max_segments = segments + 16;  // room to pay out
  auto rope = make_rope(p);
  EXPECT_TRUE(rope.ok());
  const std::vector<Vec3> line = with_slack({from, to}, (1 + slack) * straight);
  RopeEnds ends;
  ends.start_m = from;
  ends.end_m = to;
  (*rope)->set_ends(ends);
  EXPECT_TRUE((*rope)->reset(line.data(), static_cast<int>(line.size()), segments).ok());
  (*rope)->set_ends(ends);
  return std::move(*rope);
}

TEST(Rope, ParametersAreValidated) {
  RopeParams p;
  EXPECT_TRUE(validate(p).ok());
  p.mass_kg = 0;
  EXPECT_NE(validate(p).message().find("mass"), std::string::npos);
  p = RopeParams{};
  p.verlet_damping = 2;
  EXPECT_FALSE(validate(p).ok());
  p = RopeParams{};
  p.max_segments = 1;
  EXPECT_FALSE(make_rope(p).ok());
  for (const double share : {-0.1, 1.5, std::nan("")}) {
    p = RopeParams{};
    p.fire_mixing = share;
    EXPECT_NE(validate(p).message().find("FIRE mixing"), std::string::npos) << share;
    EXPECT_FALSE(params_valid(p)) << share;
  }
  p = RopeParams{};
  p.fire_mixing = 0.1;
  EXPECT_TRUE(validate(p).ok());
  p.model = RopeModel::spring;
  EXPECT_NE(validate(p).message().find("articulated rope only"), std::string::npos);
  EXPECT_FALSE(params_valid(p));
  EXPECT_TRUE(parse_rope_model("spring").ok());
  EXPECT_FALSE(parse_rope_model("noodle").ok());
}

TEST(Rope, ResetRefusesBadPaths) {
  auto rope = laid_rope(RopeModel::articulated, 8, 0.2);
  const Vec3 line[2] = {{0, 0, 0}, {100, 0, 0}};
  EXPECT_FALSE(rope->reset(line, 2, 0).ok());
  EXPECT_FALSE(rope->reset(line, 2, 100000).ok());  // above the capacity
  EXPECT_FALSE(rope->reset(line, 1, 4).ok());
  const Vec3 same[2] = {{5, 5, 5}, {5, 5, 5}};
  EXPECT_FALSE(rope->reset(same, 2, 4).ok());
  const Vec3 nan[2] = {{0, 0, 0}, {std::nan(""), 0, 0}};
  EXPECT_NE(rope->reset(nan, 2, 4).message().find("not finite"), std::string::npos);
  // ends 1 m apart in 4 segments: each shorter than kMinSegmentM
  const Vec3 close[2] = {{0, 0, 0}, {1, 0, 0}};
  const Status s = rope->reset(close, 2, 4);
  EXPECT_NE(s.message().find("use at most 2 segments"), std::string::npos) << s.message();
  // out to 100 m and back: one segment would have no length
  const Vec3 fold[3] = {{0, 0, 0}, {100, 0, 0}, {0, 0, 0}};
  EXPECT_NE(rope->reset(fold, 3, 1).message().find("folds back"), std::string::npos);
  EXPECT_EQ(rope->segments(), 8);  // unchanged by the refusals
  for (int i = 0; i <= 8; ++i) EXPECT_TRUE(rope->vertices()[i].allFinite());
}

// check_polyline, the real-time form of reset()'s check, agrees with the
// message form on every case and refuses segments shorter than kMinSegmentM.
TEST(Rope, CheckPolylineAgreesWithItsDescription) {
  const double inf = std::numeric_limits<double>::infinity();
  const Vec3 paths[][2] = {{{0, 0, 0}, {100, 0, 0}},
                           {{0, 0, 0}, {1, 0, 0}},
                           {{0, 0, 0}, {0, 0, 0}},
                           {{0, 0, 0}, {inf, 0, 0}},
                           {{std::nan(""), 0, 0}, {1, 0, 0}}};
  for (const auto& path : paths) {
    for (int segments : {0, 1, 2, 8, 200, 201, 1000}) {
      const Errc e = check_polyline(path, 2, segments, 1, 500);
      const Status s = describe_polyline(path, 2, segments, 1, 500);
      EXPECT_EQ(e == Errc::ok, s.ok()) << s.message();
      const double length = (path[1] - path[0]).norm();
      const bool ok = std::isfinite(length) && segments >= 1 && length / segments >= kMinSegmentM;
      EXPECT_EQ(e == Errc::ok, ok) << segments << " segments over " << length << " m";
    }
  }
}

TEST(Rope, ResampleSpacesPointsEquallyAlongThePath) {
  const Vec3 path[3] = {{0, 0, 0}, {30, 0, 0}, {30, 40, 0}};  // 70 m
  Vec3 out[8];
  ASSERT_TRUE(resample_polyline(path, 3, 7, out).ok());
  EXPECT_EQ(out[0], path[0]);
  EXPECT_EQ(out[7], path[2]);
  EXPECT_NEAR((out[3] - Vec3(30, 0, 0)).norm(), 0.0, 1e-9);   // 30 m along
  EXPECT_NEAR((out[5] - Vec3(30, 20, 0)).norm(), 0.0, 1e-9);  // 50 m along
}

TEST(ArticulatedRope, StaysInextensibleUnderStrongForces) {
  for (int segments : {16, 128}) {
    auto rope = laid_rope(RopeModel::articulated, segments, 0.3);
    auto& a = dynamic_cast<ArticulatedRope&>(*rope);
    const double length = a.length_m();
    const double segment = length / segments;
    Wavy field;
    double worst_gap = 0, worst_length_error = 0;
    for (int t = 0; t < 10000; ++t) {
      a.step(0.001, field);
      worst_gap = std::max(worst_gap, a.max_joint_gap_m());
      double polyline = 0;
      for (int i = 0; i < segments; ++i) polyline += (a.vertices()[i + 1] - a.vertices()[i]).norm();
      worst_length_error = std::max(worst_length_error, std::fabs(polyline - length) / length);
    }
    EXPECT_LT(worst_gap, 1e-4 * segment) << segments << " segments";
    EXPECT_LT(worst_length_error, 1e-3) << segments << " segments";
    // the fixed ends stay put
    EXPECT_LT((a.vertices()[0] - a.ends().start_m).norm(), 1e-4 * segment);
    EXPECT_LT((a.vertices()[segments] - a.ends().end_m).norm(), 1e-4 * segment);
  }
}

// Property (issue 14): for ends anywhere (coincident, sub-metre apart, a
// few metres, kilometres, 100 km) and any segment count, a rope either
// refuses the lay (leaving its state as it was) or stays finite while it
// steps in a strong field; an articulated one keeps its length.
TEST(Rope, RandomEndsAndSegmentsNeverGiveANonFinitePosition) {
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int counts[] = {2, 3, 7, 33, 64};
  int laid = 0, refused = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const RopeModel model = rng() % 2 ? RopeModel::spring : RopeModel::articulated;
    const int segments = counts[rng() % 5];
    const Vec3 from(5000 * (u(rng) - 0.5), 5000 * (u(rng) - 0.5), 500 * u(rng));
    const Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, 0.2 * (u(rng) - 0.5)).normalized();
    const double apart[] = {0.0, 0.5 * u(rng), 1 + 9 * u(rng), 300 + 3000 * u(rng), 1e5};
    const Vec3 to = from + dir * apart[rng() % 5];
    // the rope is sized as its callers size it: the segment from the ends
    // (a tiny one when they coincide), the field's reference acceleration
    const double segment_m = std::max(1.3 * (to - from).norm() / segments, 1e-3);
    RopeParams p = scaled_rope_params(model, segments, segment_m, 1.0, 1000.0);
    p.max_segments = 64;
    auto made = make_rope(p);
    ASSERT_TRUE(made.ok()) << made.status().message();
    Rope& rope = **made;
    // a rope already laid (100 m of 8 segments), whose state a refusal must keep
    const std::vector<Vec3> first = with_slack({from, from + Vec3(100, 0, 0)}, 130.0);
    ASSERT_TRUE(rope.reset(first.data(), static_cast<int>(first.size()), 8).ok());
    const std::vector<Vec3> kept(rope.vertices(), rope.vertices() + 9);
    // laid with 30% slack, as the planner and the console lay it (a taut
    // rope between fixed ends cannot take a sideways force inextensibly)
    const std::vector<Vec3> line = with_slack({from, to}, 1.3 * (to - from).norm());
    RopeEnds ends;
    ends.start_m = from;
    ends.end_m = to;
    if (!rope.reset(line.data(), static_cast<int>(line.size()), segments).ok()) {
      ++refused;
      ASSERT_EQ(rope.segments(), 8) << "trial " << trial;
      for (int i = 0; i <= 8; ++i)
        ASSERT_EQ(rope.vertices()[i], kept[static_cast<std::size_t>(i)]) << "trial " << trial;
      continue;
    }
    rope.set_ends(ends);
    ++laid;
    const double length = rope.length_m();
    Wavy field;
    for (int t = 0; t < 1000; ++t) {
      rope.step(0.001, field);
      if (t % 100 != 99) continue;
      for (int i = 0; i <= rope.segments(); ++i) {
        ASSERT_TRUE(rope.vertices()[i].allFinite()) << to_string(model) << ", trial " << trial << ", step " << t;
      }
      ASSERT_TRUE(std::isfinite(rope.kinetic_energy_j())) << "trial " << trial;
    }
    if (model == RopeModel::articulated) {
      double polyline = 0;
      for (int i = 0; i < rope.segments(); ++i) polyline += (rope.vertices()[i + 1] - rope.vertices()[i]).norm();
      EXPECT_NEAR(polyline, length, 1e-3 * length) << "trial " << trial << ", " << segments << " segments";
    }
  }
  // both outcomes were exercised: coincident and sub-metre ends are refused
  EXPECT_GT(laid, 10);
  EXPECT_GT(refused, 5);
}

TEST(Rope, EnergyStaysBoundedForAMinuteAtOneMillisecond) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto rope = laid_rope(model, 64, 0.3);
    Wavy field;
    double max_energy = 0, late_energy = 0;
    for (int t = 0; t < 60000; ++t) {
      rope->step(0.001, field);
      const double e = rope->kinetic_energy_j();
      ASSERT_TRUE(std::isfinite(e)) << to_string(model) << " at step " << t;
      max_energy = std::max(max_energy, e);
      if (t >= 50000) late_energy = std::max(late_energy, e);
    }
    // Driven by a non-conservative field the rope keeps moving, but damping
    // holds its energy: no growth after the transient.
    EXPECT_LE(late_energy, max_energy) << to_string(model);
    EXPECT_LT(max_energy, 1e9) << to_string(model);
    for (int i = 0; i <= rope->segments(); ++i) ASSERT_TRUE(rope->vertices()[i].allFinite());
  }
}

TEST(Rope, SettlesUnderAUniformPull) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto rope = laid_rope(model, 32, 0.3, {0, 0, 0}, {1000, 0, 0});
    Uniform down;
    down.a = {0, 0, -1000};
    for (int t = 0; t < 30000; ++t) rope->step(0.001, down);
    EXPECT_LT(rope->kinetic_energy_j(), 1e-3) << to_string(model);
    EXPECT_LT(rope->vertices()[16].z(), -100.0) << to_string(model);  // it sags
  }
}

// FIRE (the planner's minimiser) comes to rest where the physical rope does,
// in fewer steps, and stays inextensible and finite in a field that is no
// potential (where zeroing and turning velocities could otherwise pump).
TEST(ArticulatedRope, FireSettlesWhereThePhysicalRopeDoesInFewerSteps) {
  auto physical = laid_rope(RopeModel::articulated, 32, 0.3, {0, 0, 0}, {1000, 0, 0});
  auto fire = laid_rope(RopeModel::articulated, 32, 0.3, {0, 0, 0}, {1000, 0, 0});
  RopeParams p = fire->params();
  p.fire_mixing = kPlanFireMixing;
  p.linear_damping_per_s = p.angular_damping_per_s = kPlanFireDamping_per_s;
  ASSERT_EQ(fire->set_params(p), Errc::ok);
  Uniform down;
  down.a = {0, 0, -1000};
  // steps until at rest (kinetic energy under 1e-3 J for 200 steps running)
  auto settle = [&](Rope& rope) {
    int quiet = 0;
    for (int t = 1; t <= 30000; ++t) {
      rope.step(0.001, down);
      quiet = rope.kinetic_energy_j() < 1e-3 ? quiet + 1 : 0;
      if (quiet == 200) return t;
    }
    return 30001;
  };
  const int physical_steps = settle(*physical), fire_steps = settle(*fire);
  EXPECT_LE(physical_steps, 30000);
  EXPECT_LT(fire_steps, physical_steps);
  for (int i = 0; i <= 32; ++i) {
    EXPECT_LT((fire->vertices()[i] - physical->vertices()[i]).norm(), 1.0) << "vertex " << i;
  }
  auto& a = dynamic_cast<ArticulatedRope&>(*fire);
  const double segment = a.length_m() / 32;
  Wavy field;
  for (const double dt_s : {0.001, 0.004}) {  // the console's step and the planner's
    for (int t = 0; t < 3000; ++t) {
      a.step(dt_s, field);
      ASSERT_TRUE(std::isfinite(a.kinetic_energy_j())) << "step " << t;
      for (int i = 0; i <= 32; ++i) ASSERT_TRUE(a.vertices()[i].allFinite()) << "step " << t << " vertex " << i;
      const double gap_m = a.max_joint_gap_m();
      ASSERT_TRUE(gap_m < 1e-4 * segment) << "step " << t << ": gap " << gap_m << " m";  // false for NaN too
    }
  }
}

TEST(Rope, StepsAreDeterministic) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto a = laid_rope(model, 48, 0.3), b = laid_rope(model, 48, 0.3);
    Wavy field;
    for (int t = 0; t < 3000; ++t) {
      a->step(0.001, field);
      b->step(0.001, field);
    }
    for (int i = 0; i <= 48; ++i) ASSERT_EQ(a->vertices()[i], b->vertices()[i]) << to_string(model);
  }
}

TEST(Rope, StepAllocatesNothing) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto rope = laid_rope(model, 128, 0.3);
    Wavy field;
    rope->step(0.001, field);  // warm up
    const std::uint64_t before = visvol::testing::thread_allocation_count();
    for (int t = 0; t < 2000; ++t) {
      rope->step(0.001, field);
      rope->set_point_force(10, 0.5, Vec3(1, 2, 3));
      (void)rope->point(10, 0.5);
      (void)rope->kinetic_energy_j();
    }
    EXPECT_EQ(visvol::testing::thread_allocation_count() - before, 0u) << to_string(model);
  }
}

TEST(Rope, AGraspForcePullsTheRopeItsWay) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto rope = laid_rope(model, 32, 0.3, {0, 0, 0}, {1000, 0, 0});
    Uniform none;
    const double y0 = rope->point(16, 0.5).y();
    for (int t = 0; t < 3000; ++t) {
      rope->set_point_force(16, 0.5, Vec3(0, 400, 0));
      rope->step(0.001, none);
    }
    EXPECT_GT(rope->point(16, 0.5).y() - y0, 20.0) << to_string(model);
    EXPECT_GT(rope->point_velocity(16, 0.5).y(), -1e-6) << to_string(model);
  }
}

TEST(Rope, PaysOutLengthAtTheSpool) {
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto rope = laid_rope(model, 8, 0.0, {0, 0, 0}, {100, 0, 0});
    RopeEnds ends = rope->ends();
    ends.end_fixed = false;  // mode B: the far end is dragged
    rope->set_ends(ends);
    // bent first, so that a pay-out that moved the rope would show
    Uniform side;
    side.a = Vec3(0, 50, 0);
    for (int t = 0; t < 300; ++t) rope->step(0.001, side);
    const double before = rope->length_m();
    std::vector<Vec3> path(rope->vertices(), rope->vertices() + rope->segments() + 1);
    ASSERT_TRUE(rope->pay_out_at_start());
    EXPECT_EQ(rope->segments(), 9);
    // the path keeps its shape; the free end moves on along the last segment
    for (int i = 0; i <= 8; ++i) {
      EXPECT_LT((rope->vertices()[i] - path[static_cast<std::size_t>(i)]).norm(), 1e-6) << to_string(model) << " " << i;
    }
    const Vec3 last = path[8] - path[7];
    EXPECT_LT((rope->vertices()[9] - (path[8] + last)).norm(), 1e-6) << to_string(model);
    Uniform drag;
    for (int t = 0; t < 1000; ++t) {
      rope->set_point_force(rope->segments() - 1, 1.0, Vec3(300, 0, 0));
      rope->step(0.001, drag);
    }
    for (int i = 0; i <= rope->segments(); ++i) ASSERT_TRUE(rope->vertices()[i].allFinite());
    EXPECT_LT((rope->vertices()[0] - ends.start_m).norm(), 1e-3);   // still held at the spool
    EXPECT_GT(rope->length_m(), before + 5.0) << to_string(model);  // the paid-out length is used
  }
  RopeParams p = scaled_rope_params(RopeModel::articulated, 8, 10.0, 1.0, 1000.0);
  auto full = make_rope(p);
  const Vec3 line[2] = {{0, 0, 0}, {80, 0, 0}};
  ASSERT_TRUE((*full)->reset(line, 2, 8).ok());
  RopeEnds free_end = (*full)->ends();
  free_end.end_fixed = false;
  (*full)->set_ends(free_end);
  EXPECT_FALSE((*full)->pay_out_at_start());  // at capacity
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    auto held = laid_rope(model, 8, 0.0, {0, 0, 0}, {100, 0, 0});
    EXPECT_FALSE(held->pay_out_at_start()) << to_string(model) << ": the far end is held";
    EXPECT_EQ(held->segments(), 8);
  }
}

}  // namespace
}  // namespace visvol::rt
