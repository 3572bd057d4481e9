#include "rt/servo/servo.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cmath>
#include <random>
#include <thread>

#include "tests/support/alloc_counter.hpp"

namespace visvol::servo {
namespace {

using Eigen::Vector3d;
constexpr double kDt = 0.001;

Servo make(const ServoConfig& c = ServoConfig{}) {
  auto s = Servo::create(c);
  EXPECT_TRUE(s.ok()) << s.status().message();
  return std::move(s).value();
}

// A healthy tick at time t with the handle at `mm`.
ServoInput healthy(double t, const Vector3d& mm, bool grasp, const Vector3d& point = Vector3d::Zero()) {
  ServoInput in;
  in.time_s = t;
  in.device_pos_mm = mm;
  in.grasp_button = grasp;
  in.sample_fresh = true;
  in.sample_valid = true;
  in.device_operational = true;
  in.point_valid = true;
  in.point_pos_m = point;
  return in;
}

// Runs ticks from t over `n` ms with the input from make_in(t); returns the last output.
template <typename F>
ServoOutput run(Servo& s, double& t, int n, F make_in) {
  ServoOutput out;
  for (int i = 0; i < n; ++i) {
    t += kDt;
    out = s.step(make_in(t));
  }
  return out;
}

// Releases and presses the grasp button: the operator grasps.
ServoOutput grasp(Servo& s, double& t, const Vector3d& mm, const Vector3d& point = Vector3d::Zero()) {
  run(s, t, 2, [&](double tt) { return healthy(tt, mm, false, point); });
  return run(s, t, 1, [&](double tt) { return healthy(tt, mm, true, point); });
}

TEST(ServoConfig, DefaultsAreValidAndBadFieldsAreNamed) {
  EXPECT_TRUE(Servo::validate(ServoConfig{}).ok()) << Servo::validate(ServoConfig{}).message();
  const auto message = [](auto mutate) {
    ServoConfig c;
    mutate(c);
    return Servo::validate(c).message();
  };
  EXPECT_NE(message([](ServoConfig& c) { c.continuous_force_n = 9.0; }).find("continuous_force_n"), std::string::npos);
  EXPECT_NE(message([](ServoConfig& c) { c.slew_n_per_s = 0.0; }).find("slew_n_per_s"), std::string::npos);
  EXPECT_NE(message([](ServoConfig& c) { c.world_m_per_device_mm = std::nan(""); }).find("world_m_per_device_mm"),
            std::string::npos);
  EXPECT_NE(message([](ServoConfig& c) { c.device_to_world(0, 0) = -1.0; }).find("device_to_world"), std::string::npos)
      << "a reflection is no rotation";
  EXPECT_NE(message([](ServoConfig& c) { c.coupling_stiffness_n_per_m = 100.0; }).find("above the device's stable"),
            std::string::npos)
      << "100 N/m x 0.01 m/mm x 1000 = 1000 N/m in the hand";
  EXPECT_NE(message([](ServoConfig& c) { c.coupling_damping_n_s_per_m = 1.0; }).find("coupling_damping"),
            std::string::npos);
  EXPECT_NE(message([](ServoConfig& c) { c.world_offset_m.x() = INFINITY; }).find("world_offset_m"), std::string::npos);
}

TEST(Servo, MapsTheHandleIntoTheWorld) {
  ServoConfig c;
  c.world_offset_m = Vector3d(100.0, 200.0, 300.0);
  Servo s = make(c);
  // Device x right -> east, y up -> up, z toward the operator -> south.
  const ServoOutput out = s.step(healthy(0.0, Vector3d(10.0, 20.0, 30.0), false));
  EXPECT_TRUE(out.proxy_pos_m.isApprox(Vector3d(100.1, 199.7, 300.2), 1e-12)) << out.proxy_pos_m.transpose();
}

TEST(Servo, ClutchFreezesTheProxyAndReindexes) {
  Servo s = make();
  double t = 0.0;
  run(s, t, 5, [](double tt) { return healthy(tt, Vector3d(10, 0, 0), false); });
  auto clutched = [](double tt, double x) {
    ServoInput in = healthy(tt, Vector3d(x, 0, 0), false);
    in.clutch_button = true;
    return in;
  };
  ServoOutput out = s.step(clutched(t += kDt, 10.0));
  const Vector3d frozen = out.proxy_pos_m;
  EXPECT_TRUE(out.clutched);
  for (double x = 10.0; x > -40.0; x -= 1.0) {
    out = s.step(clutched(t += kDt, x));
    EXPECT_TRUE(out.proxy_pos_m.isApprox(frozen)) << "the hand moves back, the proxy stays";
  }
  out = s.step(healthy(t += kDt, Vector3d(-40, 0, 0), false));
  EXPECT_FALSE(out.clutched);
  EXPECT_TRUE(out.proxy_pos_m.isApprox(frozen)) << "released: continues from where it stopped";
  out = s.step(healthy(t += kDt, Vector3d(-30, 0, 0), false));
  EXPECT_NEAR(out.proxy_pos_m.x() - frozen.x(), 0.1, 1e-12) << "10 mm more = 0.1 m more";
}

// The executive's spool mode hands the operator the rope's free end: the
// handle where it is puts the proxy there, and moves it from there on; a
// non-finite point is ignored.
TEST(Servo, ReindexPutsTheProxyWhereAskedFromTheHandleAsItIs) {
  Servo s = make();
  double t = 0.0;
  run(s, t, 5, [](double tt) { return healthy(tt, Vector3d(30, -5, 12), false); });
  const Vector3d there(5000.0, -250.0, 80.0);
  s.reindex(there);
  ServoOutput out = s.step(healthy(t += kDt, Vector3d(30, -5, 12), false));
  EXPECT_TRUE(out.proxy_pos_m.isApprox(there, 1e-12)) << out.proxy_pos_m.transpose();
  out = s.step(healthy(t += kDt, Vector3d(40, -5, 12), false));
  EXPECT_NEAR(out.proxy_pos_m.x() - there.x(), 0.1, 1e-9) << "10 mm east = 0.1 m east";
  s.reindex(Vector3d(NAN, 0, 0));
  out = s.step(healthy(t += kDt, Vector3d(40, -5, 12), false));
  EXPECT_NEAR(out.proxy_pos_m.x() - there.x(), 0.1, 1e-9) << "a non-finite point changes nothing";
  s.restore_mapping();
  out = s.step(healthy(t += kDt, Vector3d(0, 0, 0), false));
  EXPECT_TRUE(out.proxy_pos_m.isApprox(ServoConfig{}.world_offset_m, 1e-12)) << "the configured mapping again";
}

// A rope laid again under the hand: the grasp ends, and forces come back only
// with a new press of the grasp button.
TEST(Servo, ReleasingTheGraspWithholdsForcesUntilTheNextPress) {
  Servo s = make();
  double t = 0.0;
  run(s, t, 5, [](double tt) { return healthy(tt, Vector3d::Zero(), false); });
  ServoOutput out = run(s, t, 400, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
  ASSERT_TRUE(out.grasping);
  ASSERT_GT(out.rope_force_n.norm(), 0.0);
  s.release_grasp();
  out = run(s, t, 50, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
  EXPECT_FALSE(out.grasping) << "the button still held is not a new grasp";
  EXPECT_TRUE(out.awaiting_regrasp);
  EXPECT_EQ(out.rope_force_n.norm(), 0.0);
  run(s, t, 5, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), false); });
  out = run(s, t, 5, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
  EXPECT_TRUE(out.grasping) << "released and pressed again";
  EXPECT_EQ(s.counters().grasps, 2u);
}

TEST(Servo, SoftJointPullsTheRopeAndTheHandFeelsTheReaction) {
  ServoConfig c;
  c.ramp_in_s = 0.0;
  c.slew_n_per_s = 1e6;
  Servo s = make(c);
  double t = 0.0;
  ServoOutput out = grasp(s, t, Vector3d::Zero());
  EXPECT_TRUE(out.grasping);
  EXPECT_TRUE(out.forces_enabled);
  // Handle 1 mm right of the grasped point: rope pulled east by K x 0.01 m = 0.4 N.
  out = s.step(healthy(t += kDt, Vector3d(1, 0, 0), true));
  EXPECT_GT(out.rope_force_n.x(), 0.39);
  // The hand is pulled back (device -x), the damper adds to it while moving.
  EXPECT_LT(out.device_force_n.x(), -0.39);
  EXPECT_NEAR(out.device_force_n.y(), 0.0, 1e-12);
  // Held still: exactly the spring.
  out = run(s, t, 200, [](double tt) { return healthy(tt, Vector3d(1, 0, 0), true); });
  EXPECT_NEAR(out.rope_force_n.x(), 0.4, 1e-6);
  EXPECT_NEAR(out.device_force_n.x(), -0.4, 1e-6);
  // A moving rope point adds damping: point moving east at 1 m/s -> -B x 1 on the rope.
  ServoInput in = healthy(t += kDt, Vector3d(1, 0, 0), true);
  in.point_vel_m_per_s = Vector3d(1, 0, 0);
  out = s.step(in);
  EXPECT_NEAR(out.rope_force_n.x(), 0.4 - 0.2, 1e-6);
}

TEST(Servo, VisibilityCueIsFeltInTheHandInDeviceAxes) {
  ServoConfig c;
  c.ramp_in_s = 0.0;
  c.slew_n_per_s = 1e6;
  c.cue_gain_n_m = -2.0;  // push toward lower visibility
  Servo s = make(c);
  double t = 0.0;
  grasp(s, t, Vector3d::Zero());
  ServoOutput out;
  for (int i = 0; i < 5; ++i) {
    ServoInput in = healthy(t += kDt, Vector3d::Zero(), true);
    in.grad_fp_per_m = Vector3d(0.0, 0.1, 0.3);  // more visible to the north and up
    out = s.step(in);
  }
  // World cue (0, -0.2, -0.6) N: south and down = device +z and -y.
  EXPECT_NEAR(out.device_force_n.z(), 0.2, 1e-9);
  EXPECT_NEAR(out.device_force_n.y(), -0.6, 1e-9);
  EXPECT_TRUE(out.rope_force_n.isZero(1e-12)) << "the cue acts on the hand, not on the rope";
}

TEST(Servo, ClampsRampsInAndLimitsSlew) {
  ServoConfig c;  // 1.4 N, 100 N/s, ramp 0.3 s
  Servo s = make(c);
  double t = 0.0;
  grasp(s, t, Vector3d(30, 0, 0));  // the handle rests 0.3 m from the grasped point
  double last = 0.0, peak = 0.0;
  for (int i = 0; i < 600; ++i) {
    const ServoOutput out = s.step(healthy(t += kDt, Vector3d(30, 0, 0), true));  // wants 12 N
    const double f = out.device_force_n.norm();
    ASSERT_LE(f, 1.4 + 1e-12);
    ASSERT_LE(std::fabs(f - last), 0.1 + 1e-12) << "100 N/s = 0.1 N per ms";
    if (i == 9) {
      EXPECT_NEAR(f, 12.0 * 0.010 / 0.3, 0.01) << "ramp: 12 N wanted, 10 ms into a 0.3 s ramp";
    }
    last = f;
    peak = std::max(peak, f);
  }
  EXPECT_NEAR(peak, 1.4, 1e-9) << "the clamp is reached";
  EXPECT_GT(s.counters().clamped_ticks, 0u);
}

TEST(Servo, EveryFaultZeroesForceInTheSameTickAndNeedsANewGrasp) {
  const auto faults = std::vector<std::pair<SafeReason, std::function<void(ServoInput&)>>>{
      {SafeReason::not_operational, [](ServoInput& in) { in.device_operational = false; }},
      {SafeReason::stale_sample, [](ServoInput& in) { in.sample_valid = false; }},
      {SafeReason::invalid_input, [](ServoInput& in) { in.point_pos_m.x() = std::nan(""); }},
      {SafeReason::invalid_input, [](ServoInput& in) { in.device_pos_mm.y() = INFINITY; }},
      {SafeReason::tick_gap, [](ServoInput& in) { in.time_s += 0.5; }},
      {SafeReason::tick_gap, [](ServoInput& in) { in.time_s -= 0.01; }},
  };
  for (const auto& [reason, inject] : faults) {
    Servo s = make();
    double t = 0.0;
    grasp(s, t, Vector3d::Zero());
    ServoOutput out = run(s, t, 400, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
    ASSERT_GT(out.device_force_n.norm(), 1.0);
    ServoInput in = healthy(t += kDt, Vector3d(20, 0, 0), true);
    inject(in);
    out = s.step(in);
    EXPECT_EQ(out.safe_reason, reason) << safe_reason_name(reason);
    EXPECT_TRUE(out.device_force_n.isZero(0.0)) << safe_reason_name(reason);
    EXPECT_TRUE(out.rope_force_n.isZero(0.0));
    EXPECT_FALSE(out.device_enable);
    EXPECT_FALSE(out.grasping);
    t = in.time_s;
    // Healthy again with the button still held: nothing.
    out = run(s, t, 500, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
    EXPECT_TRUE(out.device_force_n.isZero(0.0)) << safe_reason_name(reason);
    EXPECT_TRUE(out.awaiting_regrasp);
    // Release and press: forces come back, ramped.
    out = grasp(s, t, Vector3d(20, 0, 0), Vector3d(0.2, 0, 0));
    EXPECT_TRUE(out.grasping);
    EXPECT_FALSE(out.awaiting_regrasp);
    out = run(s, t, 400, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
    EXPECT_GT(out.device_force_n.norm(), 0.0);
  }
}

TEST(Servo, NothingUntilTheFirstPressAfterStartUp) {
  Servo s = make();
  double t = 0.0;
  const ServoOutput out = run(s, t, 300, [](double tt) { return healthy(tt, Vector3d(30, 0, 0), true); });
  EXPECT_FALSE(out.grasping);
  EXPECT_TRUE(out.awaiting_regrasp);
  EXPECT_TRUE(out.device_force_n.isZero(0.0));
}

TEST(Servo, ForceSafeStateFromAnotherThreadActsAtTheNextTick) {
  Servo s = make();
  double t = 0.0;
  grasp(s, t, Vector3d::Zero());
  ServoOutput out = run(s, t, 400, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
  ASSERT_GT(out.device_force_n.norm(), 1.0);
  std::thread([&s] { s.force_safe_state(); }).join();
  out = s.step(healthy(t += kDt, Vector3d(20, 0, 0), true));
  EXPECT_EQ(out.safe_reason, SafeReason::forced);
  EXPECT_TRUE(out.device_force_n.isZero(0.0));
  out = s.step(healthy(t += kDt, Vector3d(20, 0, 0), true));
  EXPECT_EQ(out.safe_reason, SafeReason::none) << "one request, one safe tick";
  EXPECT_TRUE(out.device_force_n.isZero(0.0)) << "but no force until a new grasp";
}

TEST(Servo, ReleasingTheGraspSlewsTheForceDown) {
  Servo s = make();
  double t = 0.0;
  grasp(s, t, Vector3d::Zero());
  run(s, t, 400, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), true); });
  ServoOutput out = s.step(healthy(t += kDt, Vector3d(20, 0, 0), false));
  EXPECT_FALSE(out.grasping);
  EXPECT_NEAR(out.device_force_n.norm(), 1.3, 1e-9) << "one 0.1 N step down";
  EXPECT_TRUE(out.device_enable) << "enable stays on while force remains";
  out = run(s, t, 14, [](double tt) { return healthy(tt, Vector3d(20, 0, 0), false); });
  EXPECT_TRUE(out.device_force_n.isZero(1e-12));
  EXPECT_FALSE(out.device_enable);
}

// Property: whatever the inputs, the force stays in the clamp, moves by at most
// slew x dt per tick unless it drops to zero, and is zero on every faulty tick.
TEST(Servo, PropertyForceStaysBoundedAndSmoothUnderRandomInputs) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    ServoConfig c;
    c.continuous_force_n = 0.5 + 3.0 * (u(rng) + 1.0);
    c.slew_n_per_s = 20.0 + 200.0 * (u(rng) + 1.0);
    c.ramp_in_s = 0.5 * (u(rng) + 1.0) * 0.4;
    c.cue_gain_n_m = 5.0 * u(rng);
    Servo s = make(c);
    double t = 0.0;
    Vector3d hand = Vector3d::Zero(), prev = Vector3d::Zero();
    bool grasp_down = false, clutch_down = false;
    for (int i = 0; i < 4000; ++i) {
      ServoInput in;
      t += kDt * ((rng() % 500 == 0) ? 40.0 : 1.0);  // rare stalls
      in.time_s = t;
      hand += Vector3d(u(rng), u(rng), u(rng)) * 0.5;
      in.device_pos_mm = hand;
      if (rng() % 300 == 0) grasp_down = !grasp_down;
      if (rng() % 700 == 0) clutch_down = !clutch_down;
      in.grasp_button = grasp_down;
      in.clutch_button = clutch_down;
      in.sample_fresh = rng() % 10 != 0;
      in.sample_valid = rng() % 800 != 0;
      in.device_operational = rng() % 900 != 0;
      in.point_valid = rng() % 1000 != 0;
      in.point_pos_m = Vector3d(u(rng), u(rng), u(rng)) * 0.3;
      in.point_vel_m_per_s = Vector3d(u(rng), u(rng), u(rng));
      in.grad_fp_per_m = Vector3d(u(rng), u(rng), u(rng));
      if (rng() % 2000 == 0) in.grad_fp_per_m.z() = std::nan("");
      if (rng() % 1500 == 0) s.force_safe_state();
      const ServoOutput out = s.step(in);
      const double f = out.device_force_n.norm();
      ASSERT_LE(f, c.continuous_force_n + 1e-12);
      if (out.safe_reason != SafeReason::none) {
        ASSERT_EQ(f, 0.0);
      }
      if (f > 0.0) {
        const double dt = std::min(in.time_s - (t - kDt), 1.0);
        ASSERT_LE((out.device_force_n - prev).norm(), c.slew_n_per_s * std::max(dt, kDt) + 1e-9);
      }
      ASSERT_TRUE(out.device_force_n.allFinite());
      ASSERT_TRUE(out.rope_force_n.allFinite());
      prev = out.device_force_n;
    }
    EXPECT_GT(s.counters().grasps, 0u);
  }
}

TEST(Servo, StepNeitherAllocatesNorFaultsPages) {
  Servo s = make();
  double t = 0.0;
  grasp(s, t, Vector3d::Zero());
  double sum = 0.0;
  const auto loop = [&] {
    for (int i = 0; i < 20000; ++i) {
      ServoInput in = healthy(t += kDt, Vector3d(5.0 + 5.0 * std::sin(i * 0.01), 0, 0), i % 3000 != 0);
      in.device_operational = i % 5000 != 4999;
      sum += s.step(in).device_force_n.norm();
    }
  };
  loop();  // warm-up: stack pages, lazily bound symbols
  rusage before{}, after{};
  getrusage(RUSAGE_THREAD, &before);
  const std::uint64_t allocs = testing::allocation_count();
  loop();
  const std::uint64_t allocated = testing::allocation_count() - allocs;
  getrusage(RUSAGE_THREAD, &after);
  EXPECT_EQ(allocated, 0u);
#ifndef VISVOL_SANITIZED
  EXPECT_EQ(after.ru_minflt - before.ru_minflt, 0) << "minor page faults in the loop";
#endif
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace visvol::servo
