// The executive tick by tick in simulated time (deterministic), and once on
// the real periodic loop across a pack much larger than its tile budget.
#include "rt/exec/executive.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

#include "../../fields/terrains.hpp"
#include "drivers/haptic/can_device.hpp"
#include "drivers/hapticsim/simulated_device.hpp"
#include "rt/exec/periodic_loop.hpp"
#include "rt/rope/point_hull_maker.hpp"
#include "storage/pack_build.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::rt {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::uint64_t kMiB = 1024 * 1024;

std::string pack_path(const std::string& stem) { return stem + "_" + std::to_string(::getpid()) + ".vvp"; }

std::string build(const std::string& stem, int posts, std::uint32_t seed) {
  const fields::Heightfield hf = fields::testing::fractal(posts, seed);
  storage::PackBuildParams p;
  p.field.nz = 32;
  p.field.ceiling_m = 200;
  p.field.range_posts = 8;
  p.lod_levels = 3;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  const std::string path = pack_path(stem);
  EXPECT_TRUE(storage::build_pack(hf, p, "", path).ok());
  return path;
}

// World point at fractions of the finest level, `up_m` above the terrain there.
Vec3 point_at(const storage::ResidentPack& r, double fx, double fy, double up_m) {
  const fields::VolumeGeometry g = r.level(0).geometry();
  const double x = g.origin_x + fx * (g.nx - 1) * g.spacing_m, y = g.origin_y - fy * (g.ny - 1) * g.spacing_m;
  return {x, y, fields::FieldSampler<storage::ResidentLevel>(r.level(0)).height(x, y) + up_m};
}

class ExecutiveTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { path_ = new std::string(build("executive", 129, 7)); }
  static void TearDownTestSuite() {
    std::remove(path_->c_str());
    delete path_;
  }
  void SetUp() override {
    auto pack = storage::Pack::open(*path_);
    ASSERT_TRUE(pack.ok());
    storage::ResidentConfig rc;
    rc.budget_bytes = 64 * kMiB;  // the whole pack
    auto r = storage::ResidentPack::create(*pack, rc);
    ASSERT_TRUE(r.ok()) << r.status().message();
    field_ = std::move(*r);
    config_.start_m = point_at(*field_, 0.15, 0.2, 150);
    config_.end_m = point_at(*field_, 0.85, 0.75, 150);
    config_.segments = 32;
    config_.max_segments = 64;
    config_.gains.clearance_m = 30;
    std::strcpy(config_.pack_id, "fractal");
  }

  std::unique_ptr<Executive> make(HapticDevice* device = nullptr, DeviceSimulation* sim = nullptr) {
    ExecutiveOutputs out;
    out.path = &paths_;
    out.limited_path = &limited_;
    out.device = &device_;
    out.acks = &acks_;
    auto e = Executive::create(config_, *field_, device, sim, &commands_, out);
    EXPECT_TRUE(e.ok()) << e.status().message();
    if (e.ok()) (*e)->warm_up();
    return e.ok() ? std::move(*e) : nullptr;
  }

  // Runs `ticks` ticks of 1 ms in simulated time.
  void run(Executive& e, int ticks) {
    for (int k = 0; k < ticks; ++k) {
      now_ns_ += kMs;
      e.tick({tick_++, now_ns_, now_ns_, kMs});
    }
  }

  msg::Command command(msg::CommandKind kind, std::uint64_t sequence) {
    msg::Command c{};
    c.kind = kind;
    c.sequence = sequence;
    msg::copy_text(c.source, "test");
    return c;
  }
  msg::CommandAck next_ack() {
    msg::CommandAck a{};
    EXPECT_TRUE(acks_.try_pop(a));
    return a;
  }
  // The reason of the next ack, which must say the command failed.
  std::string next_failure() {
    const msg::CommandAck a = next_ack();
    EXPECT_EQ(a.result, msg::AckResult::failed) << a.sequence << ": " << a.reason;
    return a.reason;
  }

  // A hull builder for `observers` beside e's loop, started.
  std::unique_ptr<ConstraintHulls> make_hulls(Executive& e, int observers) {
    auto h = ConstraintHulls::create(field_->level(0), observers);
    EXPECT_TRUE(h.ok()) << h.status().message();
    if (!h.ok()) return nullptr;
    const Status s = e.set_constraint_hulls(h->get());
    EXPECT_TRUE(s.ok()) << s.message();
    (*h)->start();
    return std::move(*h);
  }

  // Ticks until `n` hull sets are in force (the builder works beside).
  void wait_for_sets(Executive& e, std::uint64_t n) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (e.counters().hull_sets < n && std::chrono::steady_clock::now() < end) {
      run(e, 1);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  static void add(msg::Command& c, msg::ConstraintKind kind, const Vec3& p, double height_m = 0) {
    c.constraints.items[c.constraints.count++] = {kind, {p.x(), p.y(), p.z()}, height_m};
  }

  // The highest height above the finest terrain along the rope.
  double highest_agl(const Executive& e) const {
    const fields::FieldSampler<storage::ResidentLevel> ground(field_->level(0));
    double highest = -INFINITY;
    for (int i = 0; i <= e.rope().segments(); ++i) {
      const Vec3& v = e.rope().vertices()[i];
      highest = std::max(highest, v.z() - ground.height(v.x(), v.y()));
    }
    return highest;
  }

  static std::string* path_;
  std::unique_ptr<storage::ResidentPack> field_;
  ExecutiveConfig config_;
  msg::CommandQueue commands_;
  msg::AckQueue acks_;
  LatestValue<msg::PathSample> paths_;
  LatestValue<LimitedPath> limited_;  // the flyable-path fitter's hand-off
  LatestValue<msg::DeviceStatusSample> device_;
  std::int64_t now_ns_ = 10'000 * kMs;
  std::uint64_t tick_ = 0;
};
std::string* ExecutiveTest::path_ = nullptr;

TEST_F(ExecutiveTest, RefusesEndpointsOutsideThePackAndBadCapacities) {
  ExecutiveOutputs out;
  ExecutiveConfig c = config_;
  c.start_m.x() -= 1e6;
  auto e = Executive::create(c, *field_, nullptr, nullptr, nullptr, out);
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.status().message().find("start"), std::string::npos) << e.status().message();
  EXPECT_NE(e.status().message().find("outside the pack"), std::string::npos);
  c = config_;
  c.end_m.z() -= 1000;
  EXPECT_NE(Executive::create(c, *field_, nullptr, nullptr, nullptr, out).status().message().find("below the terrain"),
            std::string::npos);
  c = config_;
  c.segments = 100;  // more than the 64 reserved
  EXPECT_NE(Executive::create(c, *field_, nullptr, nullptr, nullptr, out).status().message().find("reserved"),
            std::string::npos);
}

TEST_F(ExecutiveTest, TheRopeSettlesAndPathsAreHandedOff) {
  auto e = make();
  ASSERT_TRUE(e);
  const double fc0 = e->counters().fc;
  run(*e, 15000);  // 15 simulated seconds
  const ExecutiveCounters& c = e->counters();
  EXPECT_EQ(c.ticks, 15000u);
  EXPECT_EQ(c.paths, 15000u / 20);
  EXPECT_LT(c.fc, fc0) << "hiding should lower F_c";
  const msg::PathSample* p = paths_.take();
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->vertex_count, 33u);
  EXPECT_STREQ(p->pack_id, "fractal");
  EXPECT_EQ(p->objective, msg::Objective::hide);
  EXPECT_NEAR(p->vertices[0].position.x_m, config_.start_m.x(), 1e-6);
  EXPECT_NEAR(p->vertices[32].position.y_m, config_.end_m.y(), 1e-6);
  EXPECT_NEAR(p->f_c, c.fc, 1e-12);
  EXPECT_GT(p->min_clearance_m, 0.0);
  for (std::uint32_t i = 0; i < p->vertex_count; ++i) {
    EXPECT_GE(p->vertices[i].visibility, 0.0);
    EXPECT_LE(p->vertices[i].visibility, 1.0);
  }
  if (c.converged) {
    EXPECT_GT(c.equilibrium_s, 0.0);
  }
}

TEST_F(ExecutiveTest, CommandsAreAppliedOrFailWithAReason) {
  auto e = make();
  ASSERT_TRUE(e);
  msg::Command show = command(msg::CommandKind::set_objective, 1);
  show.objective = msg::Objective::show;
  msg::Command more = command(msg::CommandKind::set_segment_count, 2);
  more.segment_count = 48;
  msg::Command too_many = command(msg::CommandKind::set_segment_count, 3);
  too_many.segment_count = 65;
  msg::Command hull = command(msg::CommandKind::set_constraints, 4);
  hull.constraints.count = 1;
  hull.constraints.items[0].kind = msg::ConstraintKind::hidden_from;
  msg::Command clearance = command(msg::CommandKind::set_constraints, 5);
  clearance.constraints.count = 1;
  clearance.constraints.items[0].kind = msg::ConstraintKind::clearance;
  clearance.constraints.items[0].height_m = 55;
  msg::Command spring = command(msg::CommandKind::set_model, 6);
  spring.model = msg::RopeModel::spring_mass;
  msg::Command terrain = command(msg::CommandKind::switch_terrain, 7);
  msg::Command stop = command(msg::CommandKind::stop, 8);
  for (const msg::Command& c : {show, more, too_many, hull, clearance, spring, terrain, stop}) {
    ASSERT_TRUE(commands_.try_push(c));
  }
  run(*e, 2);  // eight per tick at most
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  msg::CommandAck a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::applied);
  a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_EQ(a.sequence, 3u);
  EXPECT_NE(std::string(a.reason).find("reserved"), std::string::npos) << a.reason;
  a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_NE(std::string(a.reason).find("not supported"), std::string::npos) << a.reason;
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 55.0);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_STREQ(a.source, "test");
  EXPECT_EQ(a.kind, static_cast<std::uint8_t>(msg::CommandKind::switch_terrain));
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_EQ(e->rope().segments(), 48);
  EXPECT_EQ(e->rope().model(), RopeModel::spring);
  EXPECT_GT(e->forces().gains().k1_visibility, 0.0);  // show
  EXPECT_FALSE(e->counters().running);
  EXPECT_EQ(e->counters().commands_applied, 5u);
  EXPECT_EQ(e->counters().commands_failed, 3u);
  // stopped: the rope stays where it is
  const Vec3 mid = e->rope().vertices()[24];
  run(*e, 100);
  EXPECT_EQ(e->rope().vertices()[24], mid);
  ASSERT_TRUE(commands_.try_push(command(msg::CommandKind::start, 9)));
  run(*e, 1);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_TRUE(e->counters().running);
  EXPECT_EQ(e->counters().runs, 2u);
}

// A tick's command work is bounded: eight commands, and the constraint
// items of one full set-constraints command. Large sets in a burst go one a
// tick, in order, each acknowledged; small commands still go eight a tick.
TEST_F(ExecutiveTest, ABurstOfLargeConstraintSetsIsSpreadOverTicks) {
  auto e = make();
  ASSERT_TRUE(e);
  auto full_set = [&](std::uint64_t sequence, double clearance_m) {
    msg::Command c = command(msg::CommandKind::set_constraints, sequence);
    while (c.constraints.count < msg::kMaxConstraints)
      add(c, msg::ConstraintKind::clearance, Vec3::Zero(), clearance_m);
    return c;
  };
  msg::Command show = command(msg::CommandKind::set_objective, 1);
  show.objective = msg::Objective::show;
  msg::Command hide = command(msg::CommandKind::set_objective, 3);
  hide.objective = msg::Objective::hide;
  msg::Command stop = command(msg::CommandKind::stop, 5);
  for (const msg::Command& c : {show, full_set(2, 40), hide, full_set(4, 45), stop}) ASSERT_TRUE(commands_.try_push(c));
  const std::uint64_t allocations = testing::thread_allocation_count();
  // tick by tick: what was applied, the clearance then in force
  const struct {
    std::uint64_t applied;
    double clearance_m;
  } expected[] = {{1, 30}, {2, 40}, {3, 40}, {4, 45}, {5, 45}};
  for (const auto& x : expected) {
    run(*e, 1);
    EXPECT_EQ(e->counters().commands_applied, x.applied);
    EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, x.clearance_m);
  }
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  for (std::uint64_t sequence = 1; sequence <= 5; ++sequence) {
    const msg::CommandAck a = next_ack();
    EXPECT_EQ(a.sequence, sequence);
    EXPECT_EQ(a.result, msg::AckResult::applied) << a.reason;
  }
  msg::CommandAck extra{};
  EXPECT_FALSE(acks_.try_pop(extra)) << "a command acknowledged twice: " << extra.sequence;
  EXPECT_FALSE(e->counters().running);
  // two partial sets within one full set's items go in one tick
  msg::Command part_a = command(msg::CommandKind::set_constraints, 6),
               part_b = command(msg::CommandKind::set_constraints, 7);
  while (part_a.constraints.count < 200) add(part_a, msg::ConstraintKind::clearance, Vec3::Zero(), 33);
  while (part_b.constraints.count < 300) add(part_b, msg::ConstraintKind::clearance, Vec3::Zero(), 35);
  ASSERT_TRUE(commands_.try_push(part_a) && commands_.try_push(part_b));
  run(*e, 1);
  EXPECT_EQ(e->counters().commands_applied, 7u);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 35.0);
  // eight small commands fill a tick: a full set behind them waits
  for (std::uint64_t k = 0; k < 8; ++k) ASSERT_TRUE(commands_.try_push(command(msg::CommandKind::stop, 20 + k)));
  ASSERT_TRUE(commands_.try_push(full_set(28, 50)));
  run(*e, 1);
  EXPECT_EQ(e->counters().commands_applied, 15u);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 35.0);
  run(*e, 1);
  EXPECT_EQ(e->counters().commands_applied, 16u);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 50.0);
  while (acks_.try_pop(extra)) {
  }
  // ten small commands: eight in a tick, the other two in the next
  for (std::uint64_t k = 0; k < 10; ++k) ASSERT_TRUE(commands_.try_push(command(msg::CommandKind::start, 30 + k)));
  run(*e, 1);
  EXPECT_EQ(e->counters().commands_applied, 16u + kMaxCommandsPerTick);
  run(*e, 1);
  EXPECT_EQ(e->counters().commands_applied, 26u);
}

// Laying the rope again costs its vertices: with 480 segments, a burst of
// starts and segment counts goes one a tick.
TEST_F(ExecutiveTest, RopeRebuildsOfALongRopeAreSpreadOverTicks) {
  config_.segments = 480;
  config_.max_segments = 512;
  auto e = make();
  ASSERT_TRUE(e);
  msg::Command fewer = command(msg::CommandKind::set_segment_count, 3);
  fewer.segment_count = 500;
  for (const msg::Command& c : {command(msg::CommandKind::start, 1), command(msg::CommandKind::start, 2), fewer}) {
    ASSERT_TRUE(commands_.try_push(c));
  }
  const std::uint64_t allocations = testing::thread_allocation_count();
  for (std::uint64_t applied = 1; applied <= 3; ++applied) {
    run(*e, 1);
    EXPECT_EQ(e->counters().commands_applied, applied);
  }
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  EXPECT_EQ(e->rope().segments(), 500);
}

// Red-team findings (issue 14): ends too close for the segments, or not
// finite, are refused and change nothing; a refused stiffness is not kept.
TEST_F(ExecutiveTest, EndpointsTooCloseOrNotFiniteAreRefusedAndChangeNothing) {
  auto e = make();
  ASSERT_TRUE(e);
  auto endpoints = [&](std::uint64_t sequence, const Vec3& a, const Vec3& b) {
    msg::Command c = command(msg::CommandKind::set_endpoints, sequence);
    c.endpoints.start = {a.x(), a.y(), a.z()};
    c.endpoints.end = {b.x(), b.y(), b.z()};
    return c;
  };
  const Vec3 a = config_.start_m;
  ASSERT_TRUE(commands_.try_push(endpoints(1, a, a + Vec3(1, 0, 0))));  // 32 segments in 1 m
  ASSERT_TRUE(commands_.try_push(endpoints(2, a, Vec3(std::nan(""), a.y(), a.z()))));
  ASSERT_TRUE(commands_.try_push(endpoints(3, a, a + Vec3(1e300, 0, 0))));
  msg::Command stiff = command(msg::CommandKind::set_stiffness, 4);
  stiff.stiffness.stretch_n_per_m = -5;  // refused by the rope
  stiff.stiffness.bend_n_m_per_rad = 1;
  ASSERT_TRUE(commands_.try_push(stiff));
  msg::Command more = command(msg::CommandKind::set_segment_count, 5);
  more.segment_count = 40;
  ASSERT_TRUE(commands_.try_push(more));
  run(*e, 1);
  msg::CommandAck ack = next_ack();
  EXPECT_EQ(ack.result, msg::AckResult::failed);
  EXPECT_NE(std::string(ack.reason).find("too close"), std::string::npos) << ack.reason;
  for (int k = 0; k < 2; ++k) {
    ack = next_ack();
    EXPECT_EQ(ack.result, msg::AckResult::failed);
    EXPECT_NE(std::string(ack.reason).find("outside the pack or not finite"), std::string::npos) << ack.reason;
  }
  EXPECT_EQ(next_ack().result, msg::AckResult::failed);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied) << "a refused stiffness must not spoil later rope changes";
  EXPECT_EQ(e->rope().segments(), 40);
  EXPECT_EQ(e->rope().ends().start_m, config_.start_m);
  EXPECT_EQ(e->rope().ends().end_m, config_.end_m);
}

// Weights and stiffness the loop's 1 ms step cannot integrate (the intake
// accepts up to 1e6, and a console rope of 0.5 m segments diverged within
// ticks at that, until the finite-state guard laid it again): refused with a
// reason, nothing changed, and a model switch that the kept values would make
// unstable is refused too.
TEST_F(ExecutiveTest, SpringsAndGainsTheStepCannotIntegrateAreRefused) {
  auto e = make();
  ASSERT_TRUE(e);
  msg::Command heavy = command(msg::CommandKind::set_weights, 1);
  heavy.weights = {1e6, 1.0, 1.0, 1.0};
  ASSERT_TRUE(commands_.try_push(heavy));
  msg::Command stiff = command(msg::CommandKind::set_stiffness, 2);
  stiff.stiffness = {1e6, 1e9};  // past the intake's limit: the executive checks on its own
  ASSERT_TRUE(commands_.try_push(stiff));
  msg::Command soft = command(msg::CommandKind::set_stiffness, 3);
  soft.stiffness = {1e6, 1.0};  // the bend is stable; the spring model's stretch would not be
  ASSERT_TRUE(commands_.try_push(soft));
  msg::Command spring = command(msg::CommandKind::set_model, 4);
  spring.model = msg::RopeModel::spring_mass;
  ASSERT_TRUE(commands_.try_push(spring));
  msg::Command fair = command(msg::CommandKind::set_weights, 5);
  fair.weights = {2.0, 1.0, 1.0, 1.0};
  ASSERT_TRUE(commands_.try_push(fair));
  run(*e, 4);
  for (int k = 0; k < 2; ++k) {
    const msg::CommandAck ack = next_ack();
    EXPECT_EQ(ack.result, msg::AckResult::failed) << ack.sequence;
    EXPECT_NE(std::string(ack.reason).find("outside its stability margin"), std::string::npos) << ack.reason;
  }
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);  // the articulated rope has no stretch spring
  const msg::CommandAck model = next_ack();
  EXPECT_EQ(model.result, msg::AckResult::failed);
  EXPECT_NE(std::string(model.reason).find("outside its stability margin"), std::string::npos) << model.reason;
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_EQ(e->rope().model(), RopeModel::articulated);
  run(*e, 2000);
  EXPECT_EQ(e->counters().rope_resets, 0u);
  for (int i = 0; i <= e->rope().segments(); ++i) ASSERT_TRUE(e->rope().vertices()[i].allFinite()) << i;
}

// Property (issue 14): whatever a set-endpoints or set-segment-count command
// names (ends coincident, sub-metre apart, far off the pack, not finite; any
// count), each is answered applied or failed with a reason, and the rope the
// loop steps and hands off stays finite.
TEST_F(ExecutiveTest, RandomEndpointsAndSegmentCountsNeverGiveANonFiniteRope) {
  auto e = make();
  ASSERT_TRUE(e);
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int counts[] = {0, 1, 2, 3, 40, 64, 65, 5000};
  int applied = 0, failed = 0, counted = 0;
  for (std::uint64_t seq = 1; seq <= 32; ++seq) {
    msg::Command c = command(msg::CommandKind::set_endpoints, seq);
    const Vec3 a = point_at(*field_, 0.05 + 0.9 * u(rng), 0.05 + 0.9 * u(rng), 40 + 300 * u(rng));
    const Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, 0.1 * (u(rng) - 0.5)).normalized();
    Vec3 b = point_at(*field_, 0.05 + 0.9 * u(rng), 0.05 + 0.9 * u(rng), 40 + 300 * u(rng));
    switch (seq % 8) {
      case 0: b = a; break;
      case 1: b = a + dir * (0.9 * u(rng)); break;
      case 2: b = a + dir * 1e6; break;
      case 3: b.y() = std::nan(""); break;
      case 4:
      case 5:  // every count once over the run
        c.kind = msg::CommandKind::set_segment_count;
        c.segment_count = static_cast<std::uint32_t>(counts[counted++ % 8]);
        break;
      default: break;  // two points on the pack
    }
    c.endpoints.start = {a.x(), a.y(), a.z()};
    c.endpoints.end = {b.x(), b.y(), b.z()};
    ASSERT_TRUE(commands_.try_push(c));
    run(*e, 200);
    const msg::CommandAck ack = next_ack();
    EXPECT_EQ(ack.sequence, seq);
    ASSERT_TRUE(ack.result == msg::AckResult::applied || ack.result == msg::AckResult::failed) << seq;
    if (ack.result == msg::AckResult::failed) {
      EXPECT_STRNE(ack.reason, "") << seq;
    }
    (ack.result == msg::AckResult::applied ? applied : failed) += 1;
    for (int i = 0; i <= e->rope().segments(); ++i) {
      ASSERT_TRUE(e->rope().vertices()[i].allFinite()) << "after command " << seq << ": " << ack.reason;
    }
    if (const msg::PathSample* latest = paths_.take()) {
      for (std::uint32_t i = 0; i < latest->vertex_count; ++i) {
        const msg::WorldPoint& p = latest->vertices[i].position;
        ASSERT_TRUE(std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m)) << seq;
      }
    }
  }
  EXPECT_GT(applied, 4);
  EXPECT_GT(failed, 8);
}

// A rope driven unstable (springs far too stiff for the 1 ms step) is laid
// again whenever its state stops being finite: nothing non-finite is ever
// handed off, and the resets are counted.
TEST_F(ExecutiveTest, ARopeWhoseStateStopsBeingFiniteIsLaidAgain) {
  config_.refuse_unstable = false;  // the guard behind the check: let the springs through
  auto e = make();
  ASSERT_TRUE(e);
  msg::Command spring = command(msg::CommandKind::set_model, 1);
  spring.model = msg::RopeModel::spring_mass;  // explicit springs: a stiff one diverges
  ASSERT_TRUE(commands_.try_push(spring));
  msg::Command stiff = command(msg::CommandKind::set_stiffness, 2);
  stiff.stiffness.stretch_n_per_m = 1e15;
  stiff.stiffness.bend_n_m_per_rad = 1e15;
  ASSERT_TRUE(commands_.try_push(stiff));
  // refusals and resets alike allocate nothing on the loop thread
  const std::uint64_t allocations = visvol::testing::thread_allocation_count();
  msg::Command close = command(msg::CommandKind::set_endpoints, 3);
  close.endpoints.start = {config_.start_m.x(), config_.start_m.y(), config_.start_m.z()};
  close.endpoints.end = {config_.start_m.x() + 1, config_.start_m.y(), config_.start_m.z()};
  ASSERT_TRUE(commands_.try_push(close));
  for (int k = 0; k < 500; ++k) {
    run(*e, 20);
    for (int i = 0; i <= e->rope().segments(); ++i) ASSERT_TRUE(e->rope().vertices()[i].allFinite()) << k;
    if (const msg::PathSample* p = paths_.take()) {
      for (std::uint32_t i = 0; i < p->vertex_count; ++i) {
        ASSERT_TRUE(std::isfinite(p->vertices[i].position.z_m + p->vertices[i].visibility)) << k;
      }
      ASSERT_TRUE(std::isfinite(p->f_c));
    }
  }
  EXPECT_EQ(visvol::testing::thread_allocation_count() - allocations, 0u);
  // once: the recovery dropped the operator's stiffness, the cause
  EXPECT_EQ(e->counters().rope_resets, 1u) << "these springs should have driven the rope unstable, once";
  EXPECT_TRUE(e->counters().running);
}

// The hand grabs the rope in the middle of the workspace and pulls east.
const char* kPullScript =
    "0.5 move 0 0 0 0.2\n"
    "1.0 pull 60 0 0 1.0\n"
    "4.0 release\n";

// The simulated device on its in-process bus, and the console's CAN driver
// talking to it (as the console wires them).
struct SimRig {
  std::unique_ptr<hapticsim::SimulatedDevice> sim;
  std::optional<haptic::CanDevice> device;
};

std::unique_ptr<SimRig> simulated(const char* script, std::int64_t start_ns) {
  hapticsim::SimConfig sc;
  auto s = hapticsim::parse_script(script, "test script", sc.workspace_half_mm);
  EXPECT_TRUE(s.ok()) << s.status().message();
  if (!s.ok()) return nullptr;
  auto rig = std::make_unique<SimRig>();
  auto sim = hapticsim::SimulatedDevice::create(sc, *s, start_ns);
  EXPECT_TRUE(sim.ok()) << sim.status().message();
  if (!sim.ok()) return nullptr;
  rig->sim = std::move(*sim);
  auto device = haptic::CanDevice::create(haptic::DriverConfig{}, rig->sim->console_bus());
  EXPECT_TRUE(device.ok()) << device.status().message();
  if (!device.ok()) return nullptr;
  rig->device.emplace(std::move(*device));
  return rig;
}

// A device whose every answer the test chooses: what the executive makes of
// the device's state, health and command results, apart from any bus.
class FakeDevice final : public HapticDevice {
 public:
  void poll(std::int64_t now_ns) override {
    last_poll_ns = now_ns;
    ++polls;
  }
  const HapticSample& sample() const override { return sample_; }
  HapticState state() const override { return health_.state; }
  HapticHealth health() const override { return health_; }
  Errc command(const Eigen::Vector3d& force_n, bool enable) override {
    last_force_n = force_n;
    last_enable = enable;
    return answer;
  }

  HapticSample sample_;
  HapticHealth health_;
  Errc answer = Errc::ok;
  std::int64_t last_poll_ns = 0;
  int polls = 0;
  Eigen::Vector3d last_force_n = Eigen::Vector3d::Constant(NAN);
  bool last_enable = true;
};

// The distance from p to the nearest point of the rope.
double distance_to(const Rope& r, const Vec3& p) {
  double best = INFINITY;
  for (int i = 0; i < r.segments(); ++i) {
    const Vec3 a = r.vertices()[i], d = r.vertices()[i + 1] - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * d - p).norm());
  }
  return best;
}

// With the hull builder beside the loop, set-constraints puts a hidden-from
// hull in force within a few ticks of it being built, refuses a point under
// the terrain with a reason, and an empty set clears the hulls.
TEST_F(ExecutiveTest, HiddenFromAndVisibleToConstraintsComeIntoForce) {
  auto e = make();
  ASSERT_TRUE(e);
  auto hulls = make_hulls(*e, 2);
  const Vec3 p = point_at(*field_, 0.5, 0.5, 60), q = point_at(*field_, 0.3, 0.6, 80);
  msg::Command set = command(msg::CommandKind::set_constraints, 1);
  set.constraints.count = 2;
  set.constraints.items[0].kind = msg::ConstraintKind::hidden_from;
  set.constraints.items[0].position = {p.x(), p.y(), p.z()};
  set.constraints.items[1].kind = msg::ConstraintKind::visible_to;
  set.constraints.items[1].position = {q.x(), q.y(), q.z()};
  ASSERT_TRUE(commands_.try_push(set));
  // the ticks that take the command and put the hulls in force allocate nothing
  const std::uint64_t allocations = testing::thread_allocation_count();
  run(*e, 1);
  wait_for_sets(*e, 1);
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  ASSERT_EQ(e->counters().hull_sets, 1u);
  const PointHull* in_force = e->forces().hidden_from();
  ASSERT_NE(in_force, nullptr);
  ASSERT_NE(e->forces().visible_to(), nullptr);
  // the observer's eye 2 m above its point (the default eye height)
  Result<PointHull> direct = point_hull(field_->level(0), p + Vec3(0, 0, 2), "p");
  ASSERT_TRUE(direct.ok());
  if (in_force) {
    EXPECT_EQ(in_force->height_m, direct->height_m);
  }

  msg::Command under = command(msg::CommandKind::set_constraints, 2);
  under.constraints.count = 1;
  under.constraints.items[0].kind = msg::ConstraintKind::hidden_from;
  under.constraints.items[0].position = {p.x(), p.y(), p.z() - 500};
  msg::Command clear = command(msg::CommandKind::set_constraints, 3);
  ASSERT_TRUE(commands_.try_push(under));
  ASSERT_TRUE(commands_.try_push(clear));
  run(*e, 1);
  const msg::CommandAck a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_NE(std::string(a.reason).find("below the terrain"), std::string::npos) << a.reason;
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  msg::Command high = command(msg::CommandKind::set_constraints, 4);
  high.constraints.count = 1;
  high.constraints.items[0].kind = msg::ConstraintKind::visible_to;
  high.constraints.items[0].position = {p.x(), p.y(), 1e300};
  ASSERT_TRUE(commands_.try_push(high));
  run(*e, 1);
  const msg::CommandAck h = next_ack();
  EXPECT_EQ(h.result, msg::AckResult::failed);
  EXPECT_NE(std::string(h.reason).find("above 100 km"), std::string::npos) << h.reason;
  wait_for_sets(*e, 2);
  EXPECT_EQ(e->counters().hull_sets, 2u);
  EXPECT_EQ(e->forces().hidden_from(), nullptr);
  EXPECT_EQ(e->forces().visible_to(), nullptr);
  hulls->stop();
}

// Many observers of each kind in one command (more than the eight a command
// held before the hulls were folded): every one's hull is in force, folded
// into one a kind (the lowest hidden-from, the highest visible-to hull), with
// no allocation on the ticks that take the command and put the set in force.
TEST_F(ExecutiveTest, ManyObserversOfEachKindComeIntoForceFolded) {
  auto e = make();
  ASSERT_TRUE(e);
  auto hulls = make_hulls(*e, 15);
  ASSERT_TRUE(hulls);
  msg::Command set = command(msg::CommandKind::set_constraints, 1);
  std::vector<Vec3> hidden;
  for (int k = 0; k < 12; ++k) {
    hidden.push_back(point_at(*field_, 0.1 + 0.07 * k, 0.85 - 0.06 * k, 20.0 + 5.0 * k));
  }
  const Vec3 visible[3] = {point_at(*field_, 0.3, 0.6, 80), point_at(*field_, 0.7, 0.7, 30),
                           point_at(*field_, 0.4, 0.1, 50)};
  for (const Vec3& p : hidden) add(set, msg::ConstraintKind::hidden_from, p);
  for (const Vec3& p : visible) add(set, msg::ConstraintKind::visible_to, p);
  add(set, msg::ConstraintKind::clearance, Vec3::Zero(), 25);
  ASSERT_TRUE(commands_.try_push(set));
  const std::uint64_t allocations = testing::thread_allocation_count();
  wait_for_sets(*e, 1);
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  ASSERT_EQ(e->counters().hull_sets, 1u);
  ASSERT_EQ(e->forces().hidden_from_count(), 1);
  ASSERT_EQ(e->forces().visible_to_count(), 1);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 25.0);
  // the path with its limits goes to the fitter in one hand-off, allocating nothing
  while (limited_.take() != nullptr) {
  }
  const std::uint64_t before_hand_off = testing::thread_allocation_count();
  run(*e, 2 * config_.path_every_ticks);
  EXPECT_EQ(testing::thread_allocation_count(), before_hand_off);
  const LimitedPath* lp = limited_.take();
  const msg::PathSample* sent = paths_.take();
  ASSERT_TRUE(lp != nullptr && sent != nullptr);
  EXPECT_EQ(lp->path.sequence, sent->sequence);  // the same path, not one before or after
  EXPECT_EQ(lp->path.vertex_count, sent->vertex_count);
  EXPECT_DOUBLE_EQ(lp->limits.gains.clearance_m, 25.0);
  EXPECT_EQ(lp->limits.observers.hidden_count, 12);
  EXPECT_EQ(lp->limits.observers.visible_count, 3);
  EXPECT_EQ(lp->limits.observers.sequence, e->hulls_in_force()->sequence());
  // the folds, post by post, of every observer's own hull
  std::vector<float> lowest, highest;
  auto fold = [](std::vector<float>& into, const std::vector<float>& h, bool low) {
    if (into.empty()) return void(into = h);
    for (std::size_t i = 0; i < h.size(); ++i) into[i] = low ? std::min(into[i], h[i]) : std::max(into[i], h[i]);
  };
  for (const Vec3& p : hidden) {
    Result<PointHull> h = point_hull(field_->level(0), p + Vec3(0, 0, 2), "h");
    ASSERT_TRUE(h.ok());
    fold(lowest, h->height_m, true);
  }
  for (const Vec3& p : visible) {
    Result<PointHull> v = point_hull(field_->level(0), p + Vec3(0, 0, 2), "v");
    ASSERT_TRUE(v.ok());
    fold(highest, v->height_m, false);
  }
  const PointHull* hidden_hull = e->forces().hidden_from(0);
  const PointHull* visible_hull = e->forces().visible_to(0);
  ASSERT_TRUE(hidden_hull != nullptr && visible_hull != nullptr);
  EXPECT_TRUE(hidden_hull->height_m == lowest);
  EXPECT_TRUE(visible_hull->height_m == highest);
  const HullSet* in_force = e->hulls_in_force();
  ASSERT_NE(in_force, nullptr);
  EXPECT_EQ(in_force->request.hidden_from_m[11][0], hidden[11].x());
  EXPECT_EQ(in_force->request.visible_to_m[1][1], visible[1].y());
  EXPECT_FALSE(e->hulls_pending());
  hulls->stop();
}

// Observers of the configuration are requested when the builder is given,
// and refused when they are more than it reserved.
TEST_F(ExecutiveTest, ConfiguredObserversComeIntoForceWithTheBuilder) {
  config_.eye_height_m = 5;
  ASSERT_TRUE(config_.observers.add_hidden_from(point_at(*field_, 0.5, 0.5, 10)));
  ASSERT_TRUE(config_.observers.add_hidden_from(point_at(*field_, 0.6, 0.4, 10)));
  ASSERT_TRUE(config_.observers.add_visible_to(point_at(*field_, 0.3, 0.3, 10)));
  auto e = make();
  ASSERT_TRUE(e);
  auto small = ConstraintHulls::create(field_->level(0), 2);
  ASSERT_TRUE(small.ok());
  const Status refused = e->set_constraint_hulls(small->get());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("3 hidden-from and visible-to points, the console takes 2"), std::string::npos)
      << refused.message();
  EXPECT_FALSE(e->set_constraint_hulls(nullptr).ok());
  auto hulls = make_hulls(*e, 3);
  ASSERT_TRUE(hulls);
  EXPECT_TRUE(e->hulls_pending());
  wait_for_sets(*e, 1);
  EXPECT_FALSE(e->hulls_pending());
  EXPECT_EQ(e->forces().hidden_from_count(), 1);  // the two folded into one
  EXPECT_EQ(e->forces().visible_to_count(), 1);
  EXPECT_EQ(e->hulls_in_force()->hidden_count(), 2);
  ASSERT_NE(e->hulls_in_force(), nullptr);
  EXPECT_EQ(e->hulls_in_force()->request.eye_height_m, 5.0);
  hulls->stop();

  // an observer outside the pack or under the terrain: create() says which
  ExecutiveConfig c = config_;
  c.observers.visible_to_m[0][2] -= 100;
  auto under = Executive::create(c, *field_, nullptr, nullptr, nullptr, ExecutiveOutputs{});
  ASSERT_FALSE(under.ok());
  EXPECT_NE(under.status().message().find("visible-to point"), std::string::npos) << under.status().message();
  EXPECT_NE(under.status().message().find("below the terrain"), std::string::npos) << under.status().message();
  // or 1e300 m up (a mistyped number)
  c = config_;
  c.observers.visible_to_m[0][2] = 1e300;
  auto high = Executive::create(c, *field_, nullptr, nullptr, nullptr, ExecutiveOutputs{});
  ASSERT_FALSE(high.ok());
  EXPECT_NE(high.status().message().find("visible-to point 1: Z 1e+300 m is above the 100000 m an observer may be"),
            std::string::npos)
      << high.status().message();
}

// Commands that cannot be had fail with a reason and change nothing.
TEST_F(ExecutiveTest, BadConstraintsFailWithAReasonAndChangeNothing) {
  config_.gains.max_agl_m = 400;
  auto e = make();
  ASSERT_TRUE(e);
  auto hulls = make_hulls(*e, 2);
  ASSERT_TRUE(hulls);
  const Vec3 p = point_at(*field_, 0.5, 0.5, 60);
  msg::Command three = command(msg::CommandKind::set_constraints, 1);
  for (int k = 0; k < 3; ++k) add(three, msg::ConstraintKind::visible_to, p);
  add(three, msg::ConstraintKind::clearance, Vec3::Zero(), 45);
  msg::Command too_many = command(msg::CommandKind::set_constraints, 2);  // one more than a kind holds
  for (int k = 0; k <= kMaxObserversPerKind; ++k) add(too_many, msg::ConstraintKind::hidden_from, p);
  msg::Command low = command(msg::CommandKind::set_constraints, 3);  // under the clearance in force (30 m)
  add(low, msg::ConstraintKind::max_agl, Vec3::Zero(), 20);
  msg::Command both = command(msg::CommandKind::set_constraints, 4);  // under the clearance it sets
  add(both, msg::ConstraintKind::max_agl, Vec3::Zero(), 100);
  add(both, msg::ConstraintKind::clearance, Vec3::Zero(), 120);
  msg::Command over_ends = command(msg::CommandKind::set_constraints, 5);  // the ends are 150 m up
  add(over_ends, msg::ConstraintKind::max_agl, Vec3::Zero(), 100);
  msg::Command datum = command(msg::CommandKind::set_constraints, 6);
  add(datum, msg::ConstraintKind::max_altitude, Vec3::Zero(), config_.start_m.z() - 10);
  msg::Command nan = command(msg::CommandKind::set_constraints, 7);
  add(nan, msg::ConstraintKind::max_agl, Vec3::Zero(), std::nan(""));
  msg::Command outside = command(msg::CommandKind::set_constraints, 8);
  add(outside, msg::ConstraintKind::hidden_from, p + Vec3(1e6, 0, 0));
  for (const msg::Command& c : {three, too_many, low, both, over_ends, datum, nan, outside}) {
    ASSERT_TRUE(commands_.try_push(c));
  }
  const std::uint64_t allocations = testing::thread_allocation_count();
  run(*e, 1);
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  EXPECT_NE(next_failure().find("than the console takes (--max-observers)"), std::string::npos);
  EXPECT_NE(next_failure().find("more than 256 hidden-from"), std::string::npos);
  EXPECT_NE(next_failure().find("max-agl is not above the clearance"), std::string::npos);
  EXPECT_NE(next_failure().find("max-agl is not above the clearance"), std::string::npos);
  EXPECT_NE(next_failure().find("ends are above that ceiling"), std::string::npos);
  EXPECT_NE(next_failure().find("ends are above that ceiling"), std::string::npos);
  EXPECT_NE(next_failure().find("not a height"), std::string::npos);
  EXPECT_NE(next_failure().find("outside the pack"), std::string::npos);
  EXPECT_EQ(e->counters().commands_failed, 8u);
  EXPECT_DOUBLE_EQ(e->forces().gains().clearance_m, 30.0);
  EXPECT_DOUBLE_EQ(e->forces().gains().max_agl_m, 400.0);
  EXPECT_TRUE(std::isinf(e->forces().gains().max_altitude_m));
  EXPECT_FALSE(e->hulls_pending());

  // a ceiling in force: endpoints above it are refused
  msg::Command ceiling = command(msg::CommandKind::set_constraints, 9);
  add(ceiling, msg::ConstraintKind::max_agl, Vec3::Zero(), 160);
  add(ceiling, msg::ConstraintKind::max_altitude, Vec3::Zero(), 5000);
  msg::Command high = command(msg::CommandKind::set_endpoints, 10);
  const Vec3 a = point_at(*field_, 0.2, 0.2, 100), b = point_at(*field_, 0.7, 0.6, 170);
  high.endpoints = {{a.x(), a.y(), a.z()}, {b.x(), b.y(), b.z()}};
  ASSERT_TRUE(commands_.try_push(ceiling));
  ASSERT_TRUE(commands_.try_push(high));
  run(*e, 1);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_DOUBLE_EQ(e->forces().gains().max_agl_m, 160.0);
  EXPECT_DOUBLE_EQ(e->forces().gains().max_altitude_m, 5000.0);
  EXPECT_NE(next_failure().find("above the ceiling"), std::string::npos);
  hulls->stop();

  // the configuration is checked alike
  ExecutiveConfig c = config_;
  c.gains.max_agl_m = 20;
  auto bad = Executive::create(c, *field_, nullptr, nullptr, nullptr, ExecutiveOutputs{});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("is not above the clearance"), std::string::npos) << bad.status().message();
  c.gains.max_agl_m = 100;  // the ends are 150 m up
  bad = Executive::create(c, *field_, nullptr, nullptr, nullptr, ExecutiveOutputs{});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("above the ceiling"), std::string::npos) << bad.status().message();
}

// Showing pulls the rope up (F_p grows upward); a max-agl set by command
// holds it under the ceiling, where the same run without one climbs above.
TEST_F(ExecutiveTest, ACeilingKeepsTheRopeUnderMaxAgl) {
  constexpr double kMaxAglM = 90;
  config_.objective = Objective::show;
  config_.model = RopeModel::spring;
  config_.start_m = point_at(*field_, 0.3, 0.4, 60);
  config_.end_m = point_at(*field_, 0.7, 0.6, 60);
  auto free = make();
  ASSERT_TRUE(free);
  run(*free, 8000);
  EXPECT_GT(highest_agl(*free), kMaxAglM + 20) << "without a ceiling showing should climb above it";

  auto held = make();
  ASSERT_TRUE(held);
  msg::Command ceiling = command(msg::CommandKind::set_constraints, 1);
  add(ceiling, msg::ConstraintKind::max_agl, Vec3::Zero(), kMaxAglM);
  ASSERT_TRUE(commands_.try_push(ceiling));
  run(*held, 8000);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_DOUBLE_EQ(held->forces().gains().max_agl_m, kMaxAglM);
  EXPECT_LE(highest_agl(*held), kMaxAglM);
  EXPECT_GT(held->counters().fc, 0.0);
}

// switch-terrain to another pack is handed to the console once; the pack
// it is on, a second switch while one is under way and no pack are refused.
TEST_F(ExecutiveTest, ASwitchTerrainCommandIsHandedToTheConsole) {
  auto e = make();
  ASSERT_TRUE(e);
  char id[msg::kPackIdCapacity];
  EXPECT_FALSE(e->terrain_switch(id));
  msg::Command same = command(msg::CommandKind::switch_terrain, 1);
  msg::copy_text(same.pack_id, "fractal");
  msg::Command other = command(msg::CommandKind::switch_terrain, 2);
  msg::copy_text(other.pack_id, "taunus");
  msg::Command again = command(msg::CommandKind::switch_terrain, 3);
  msg::copy_text(again.pack_id, "sf_north");
  for (const msg::Command& c : {same, other, again}) ASSERT_TRUE(commands_.try_push(c));
  const std::uint64_t allocations = testing::thread_allocation_count();
  run(*e, 1);
  EXPECT_EQ(testing::thread_allocation_count(), allocations);
  msg::CommandAck a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_NE(std::string(a.reason).find("already"), std::string::npos) << a.reason;
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  a = next_ack();
  EXPECT_EQ(a.result, msg::AckResult::failed);
  EXPECT_NE(std::string(a.reason).find("under way"), std::string::npos) << a.reason;
  ASSERT_TRUE(e->terrain_switch(id));
  EXPECT_STREQ(id, "taunus");
  EXPECT_TRUE(e->counters().running);  // the rope keeps stepping until the console ends the session
}

TEST_F(ExecutiveTest, TheOperatorPullsTheRopeThroughTheDevice) {
  auto still_sim = simulated("", now_ns_);
  ASSERT_TRUE(still_sim);
  auto still = make(&*still_sim->device, still_sim->sim.get());
  ASSERT_TRUE(still);
  const std::int64_t t0 = now_ns_;
  run(*still, 1500);

  now_ns_ = t0;
  auto pull_sim = simulated(kPullScript, now_ns_);
  ASSERT_TRUE(pull_sim);
  auto pulled = make(&*pull_sim->device, pull_sim->sim.get());
  ASSERT_TRUE(pulled);
  run(*pulled, 1500);  // half way through the pull
  EXPECT_EQ(pulled->counters().grasps, 1u);
  EXPECT_EQ(pulled->counters().device_state, HapticState::operational);
  // the grasped point follows the proxy (hundreds of metres away when the
  // hand grasped): the rope is much nearer to it than the rope nobody touched
  const Vec3 proxy = pulled->proxy_m();
  EXPECT_LT(distance_to(pulled->rope(), proxy), 0.5 * distance_to(still->rope(), proxy));
  run(*pulled, 2000);
  // the hand felt the rope, within the clamp
  EXPECT_GT(pull_sim->sim->device().counters().max_force_n, 0.1);
  EXPECT_LE(pull_sim->sim->device().counters().max_force_n, 1.4 + 1e-9);
  const msg::DeviceStatusSample* d = device_.take();
  ASSERT_NE(d, nullptr);
  EXPECT_STREQ(d->device, "haptic");
  EXPECT_GT(d->can_rx_frames, 3000u);
}

// The device-status message says what the device's interface says, and only
// a command the device refuses for another reason than its state counts as a
// send failure (the driver refuses every command until the device speaks).
TEST_F(ExecutiveTest, ReportsTheDeviceAsItsInterfaceSays) {
  FakeDevice dev;
  dev.health_ = {HapticState::fault, 0x12, 61.5, 1234, 567, 8, 3};
  dev.sample_.timestamp_ns = now_ns_;
  config_.device_every_ticks = 10;
  auto e = make(&dev);
  ASSERT_TRUE(e);
  dev.answer = Errc::state;
  run(*e, 10);
  EXPECT_EQ(dev.polls, 10);
  EXPECT_EQ(dev.last_poll_ns, now_ns_);
  EXPECT_FALSE(dev.last_enable);  // a faulty device gets no force
  EXPECT_EQ(dev.last_force_n, Eigen::Vector3d::Zero());
  EXPECT_EQ(e->counters().send_failures, 0u);
  EXPECT_EQ(e->counters().device_state, HapticState::fault);
  const msg::DeviceStatusSample* d = device_.take();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->state, msg::DeviceState::fault);
  EXPECT_EQ(d->fault_bits, 0x12u);
  EXPECT_EQ(d->motor_temperature_c, 61.5);
  EXPECT_EQ(d->can_rx_frames, 1234u);
  EXPECT_EQ(d->can_tx_frames, 567u);
  EXPECT_EQ(d->can_errors, 8u);
  EXPECT_EQ(d->bus_off_count, 3u);
  EXPECT_NEAR(d->last_position_age_ms, 10.0, 1e-9);  // the sample is ten ticks old

  dev.answer = Errc::io;  // the bus refused them
  run(*e, 10);
  EXPECT_EQ(e->counters().send_failures, 10u);

  // connected, no valid position: no force, so idle; not yet heard: disconnected
  dev.health_.state = HapticState::operational;
  run(*e, 10);
  d = device_.take();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->state, msg::DeviceState::idle);
  dev.health_.state = HapticState::boot;
  run(*e, 10);
  d = device_.take();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->state, msg::DeviceState::disconnected);
}

// A session's end (SIGTERM, Ctrl-C, time up): the loop's last act leaves the
// device at zero force, disabled; a bus that refuses it is counted.
TEST_F(ExecutiveTest, StoppingLeavesTheDeviceAtZeroForceDisabled) {
  FakeDevice dev;
  dev.health_.state = HapticState::operational;
  auto e = make(&dev);
  ASSERT_TRUE(e);
  run(*e, 10);
  dev.last_force_n = Eigen::Vector3d(0.4, -0.2, 0.9);  // as if the servo were pushing
  dev.last_enable = true;
  e->stopping();
  EXPECT_EQ(dev.last_force_n, Eigen::Vector3d::Zero());
  EXPECT_FALSE(dev.last_enable);
  const std::uint64_t failures = e->counters().send_failures;
  dev.answer = Errc::io;
  e->stopping();
  EXPECT_EQ(e->counters().send_failures, failures + 1);
}

TEST_F(ExecutiveTest, TheSafeStateZeroesTheForceUntilTheNextGrasp) {
  auto sim = simulated("0.5 move 0 0 0 0.2\n1.0 pull 60 0 0 1.0\n", now_ns_);
  ASSERT_TRUE(sim);
  auto e = make(&*sim->device, sim->sim.get());
  ASSERT_TRUE(e);
  run(*e, 1800);  // pulling: force on the hand
  ASSERT_TRUE(e->servo());
  ASSERT_GT(sim->sim->device().motor_force_n()[0] * sim->sim->device().motor_force_n()[0] +
                sim->sim->device().motor_force_n()[2] * sim->sim->device().motor_force_n()[2],
            1e-4);
  e->safe_state();
  run(*e, 1);
  EXPECT_EQ(e->counters().safe_states, 1u);
  EXPECT_EQ(e->counters().servo_reason, servo::SafeReason::forced);
  run(*e, 500);  // still holding the button: no force comes back
  EXPECT_EQ(e->counters().grasps, 1u);
  const auto& f = sim->sim->device().motor_force_n();
  EXPECT_EQ(f[0], 0.0);
  EXPECT_EQ(f[1], 0.0);
  EXPECT_EQ(f[2], 0.0);
  EXPECT_TRUE(e->counters().running) << "the rope keeps stepping in the safe state";
}

// Spool mode (the paper's mode B), driven as an operator would: the mode
// button, then the grasp of the lead's free end and one drag past the end.
// The rope pays out as it is pulled taut, settles as it goes, arrives and is
// held at the end; the path updates say so.
std::string spool_script(const ExecutiveConfig& c, double spacing_m) {
  const Eigen::Vector3d by = spool_drag_mm(c, spacing_m, 0.1);
  char text[256];
  std::snprintf(text, sizeof text,
                "0.1 move -60 10 20 0.1\n0.3 mode on\n0.4 mode off\n1.0 drag %.2f %.2f %.2f 3.0 60\n4.5 release\n",
                by.x(), by.y(), by.z());
  return text;
}

TEST_F(ExecutiveTest, SpoolModePaysOutAsTheOperatorDragsAndArrives) {
  const std::string script = spool_script(config_, field_->level(0).geometry().spacing_m);
  auto sim = simulated(script.c_str(), now_ns_);
  ASSERT_TRUE(sim);
  auto e = make(&*sim->device, sim->sim.get());
  ASSERT_TRUE(e);
  run(*e, 50);                    // warm
  std::uint64_t allocations = 0;  // by the ticks alone (the test's own checks allocate)
  const auto ticks = [&](int n) {
    const std::uint64_t before = visvol::testing::thread_allocation_count();
    run(*e, n);
    allocations += visvol::testing::thread_allocation_count() - before;
  };
  ticks(850);  // the button pressed and released, the hand at the lead's end
  ASSERT_EQ(e->counters().mode, msg::InteractionMode::spool) << script;
  EXPECT_EQ(e->counters().mode_switches, 1u);
  EXPECT_EQ(e->rope().segments(), kSpoolLeadSegments);
  const double segment_m = e->rope().length_m() / kSpoolLeadSegments;
  // the handle holds the proxy at the lead's free end (the workspace re-indexed)
  EXPECT_LT((e->proxy_m() - e->rope().point(kSpoolLeadSegments - 1, 1.0)).norm(), 0.5 * segment_m);

  ticks(1500);  // half way through the drag
  const ExecutiveCounters& mid = e->counters();
  EXPECT_GT(e->rope().segments(), kSpoolLeadSegments + 4) << "paid out while dragged";
  EXPECT_NEAR(mid.spool_paid_out_m, e->rope().segments() * segment_m, 1e-6 * segment_m * e->rope().segments());
  EXPECT_FALSE(mid.spool_arrived);
  EXPECT_GT(mid.spool_gap_m, segment_m);
  EXPECT_LT((e->rope().point(0, 0.0) - config_.start_m).norm(), 0.01 * segment_m) << "held at the start";
  const msg::PathSample* p = paths_.take();
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->mode, msg::InteractionMode::spool);
  EXPECT_GT(p->spool_paid_out_m, kSpoolLeadSegments * segment_m);

  // set-model and set-segments wait for the spool to end
  msg::Command spring = command(msg::CommandKind::set_model, 1);
  spring.model = msg::RopeModel::spring_mass;
  ASSERT_TRUE(commands_.try_push(spring));
  ticks(1);
  EXPECT_NE(next_failure().find("switch to pull mode first"), std::string::npos);

  ticks(3000);  // the drag ends past the end, the hand lets go
  const ExecutiveCounters& c = e->counters();
  EXPECT_TRUE(c.spool_arrived);
  EXPECT_FALSE(c.spool_at_capacity);
  EXPECT_EQ(c.mode, msg::InteractionMode::spool);
  EXPECT_EQ(c.spool_segments, e->rope().segments());
  EXPECT_EQ(c.spool_gap_m, 0.0);
  const Vec3 last = e->rope().point(e->rope().segments() - 1, 1.0);  // the capsule's end, not the anchor
  EXPECT_LT((last - config_.end_m).norm(), 0.05 * segment_m) << "held at the end";
  EXPECT_LT((e->rope().point(0, 0.0) - config_.start_m).norm(), 0.05 * segment_m) << "and at the start";
  EXPECT_GE(c.spool_paid_out_m, 1.02 * (config_.end_m - config_.start_m).norm() - 1e-6) << "with some slack";
  for (int i = 0; i <= e->rope().segments(); ++i) ASSERT_TRUE(e->rope().vertices()[i].allFinite());

  // back to pull mode: the arrived rope is kept, both ends held
  const int segments = e->rope().segments();
  msg::Command pull = command(msg::CommandKind::set_mode, 2);
  pull.mode = msg::InteractionMode::pull;
  ASSERT_TRUE(commands_.try_push(pull));
  ticks(1);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_EQ(e->counters().mode, msg::InteractionMode::pull);
  EXPECT_EQ(e->counters().mode_switches, 2u);
  EXPECT_EQ(e->rope().segments(), segments);
  ticks(20);
  // the whole course, button, lead, pay-outs, arrival, the switch back, allocated nothing
  EXPECT_EQ(allocations, 0u);
  p = paths_.take();
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->mode, msg::InteractionMode::pull);
  EXPECT_EQ(p->spool_paid_out_m, 0.0);
}

// A mode switch under a held grasp lets go: the new rope is not pulled until
// the operator presses the grasp button again; a held mode button seen again
// after samples that were not valid is not a second press.
TEST_F(ExecutiveTest, AModeSwitchLetsGoOfTheGraspAndAHeldButtonSwitchesOnce) {
  FakeDevice dev;
  dev.health_.state = HapticState::operational;
  dev.sample_.valid = true;
  dev.sample_.fresh = true;
  auto e = make(&dev);
  ASSERT_TRUE(e);
  auto tick = [&](int n) {
    for (int k = 0; k < n; ++k) {
      dev.sample_.timestamp_ns = now_ns_ + kMs;
      run(*e, 1);
    }
  };
  tick(20);
  dev.sample_.grasp_button = true;  // pressed after a release: a grasp
  dev.sample_.position_mm = Eigen::Vector3d(30, 0, 0);
  tick(400);
  const servo::Servo* servo = e->servo();
  ASSERT_NE(servo, nullptr);
  ASSERT_EQ(servo->counters().grasps, 1u);
  dev.sample_.mode_button = true;
  tick(1);
  ASSERT_EQ(e->counters().mode, msg::InteractionMode::spool);
  dev.sample_.mode_button = false;  // a bounce within the guard time
  tick(1);
  dev.sample_.mode_button = true;
  tick(1);
  EXPECT_EQ(e->counters().mode_switches, 1u);
  tick(300);  // the grasp button still held
  EXPECT_EQ(e->rope().segments(), kSpoolLeadSegments) << "nobody pulls the lead out";
  EXPECT_EQ(servo->counters().grasps, 1u);
  EXPECT_EQ(e->counters().grasps, 1u) << "the held button did not grasp the new rope";
  EXPECT_EQ(dev.last_force_n.norm(), 0.0) << "forces withheld until a new press";
  dev.sample_.valid = false;  // a gap in the samples, the mode button still down
  tick(5);
  dev.sample_.valid = true;
  tick(300);
  EXPECT_EQ(e->counters().mode, msg::InteractionMode::spool) << "the held button switched once";
  EXPECT_EQ(e->counters().mode_switches, 1u);
  dev.sample_.mode_button = false;
  tick(1);
  dev.sample_.mode_button = true;  // a press well after the last: pull mode, the rope laid between the ends
  tick(1);
  EXPECT_EQ(e->counters().mode, msg::InteractionMode::pull);
  EXPECT_EQ(e->counters().mode_switches, 2u);
  EXPECT_EQ(e->rope().segments(), config_.segments);
}

// Spool mode needs the operator's hand; pull mode from spool mode before the
// rope arrived lays the rope between the ends again.
TEST_F(ExecutiveTest, SpoolModeWithoutADeviceIsRefusedAndPullLaysTheRopeAgain) {
  auto bare = make();
  ASSERT_TRUE(bare);
  msg::Command spool = command(msg::CommandKind::set_mode, 1);
  spool.mode = msg::InteractionMode::spool;
  ASSERT_TRUE(commands_.try_push(spool));
  run(*bare, 1);
  EXPECT_NE(next_failure().find("needs the haptic device"), std::string::npos);
  EXPECT_EQ(bare->counters().mode, msg::InteractionMode::pull);
  EXPECT_EQ(bare->rope().segments(), config_.segments);

  FakeDevice dev;
  dev.health_.state = HapticState::operational;
  auto e = make(&dev);
  ASSERT_TRUE(e);
  ASSERT_TRUE(commands_.try_push(spool));
  run(*e, 1);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_EQ(e->rope().segments(), kSpoolLeadSegments);
  run(*e, 200);  // nobody drags: nothing pays out
  EXPECT_EQ(e->rope().segments(), kSpoolLeadSegments);
  msg::Command pull = command(msg::CommandKind::set_mode, 2);
  pull.mode = msg::InteractionMode::pull;
  ASSERT_TRUE(commands_.try_push(pull));
  run(*e, 1);
  EXPECT_EQ(next_ack().result, msg::AckResult::applied);
  EXPECT_EQ(e->rope().segments(), config_.segments);
  EXPECT_NEAR((e->rope().vertices()[config_.segments] - config_.end_m).norm(), 0.0, 1.0);
  EXPECT_EQ(e->counters().mode_switches, 2u);
}

TEST_F(ExecutiveTest, TicksAllocateNothing) {
  auto sim = simulated(kPullScript, now_ns_);
  ASSERT_TRUE(sim);
  auto e = make(&*sim->device, sim->sim.get());
  ASSERT_TRUE(e);
  run(*e, 500);  // warm
  msg::Command show = command(msg::CommandKind::set_objective, 1);
  show.objective = msg::Objective::show;
  ASSERT_TRUE(commands_.try_push(show));
  const std::uint64_t before = visvol::testing::thread_allocation_count();
  run(*e, 5000);  // grasp, pull, release, commands, hand-offs
  EXPECT_EQ(visvol::testing::thread_allocation_count() - before, 0u);
  EXPECT_EQ(e->counters().grasps, 1u);
}

// A wrapper that counts what the loop thread allocates while ticking.
class CountingExecutive final : public PeriodicTask {
 public:
  explicit CountingExecutive(Executive& e) : e_(e) {}
  void warm_up() override {
    e_.warm_up();
    (void)visvol::testing::thread_allocation_count();  // its thread-local counter's first touch
  }
  void tick(const TickTime& t) override {
    if (t.index == 200) start_ = visvol::testing::thread_allocation_count();  // after warm-up
    e_.tick(t);
    if (t.index >= 200) allocations_.store(visvol::testing::thread_allocation_count() - start_);
    ticks_.store(t.index + 1, std::memory_order_relaxed);
  }
  void safe_state() override { e_.safe_state(); }
  std::uint64_t allocations() const { return allocations_.load(); }
  std::uint64_t ticks() const { return ticks_.load(std::memory_order_relaxed); }
  // Waits at least `at_least`, and until `count` more ticks have run (a slow,
  // sanitized or loaded machine runs fewer a second), 10 s at most.
  void wait_ticks(std::uint64_t count, std::chrono::milliseconds at_least) const {
    const std::uint64_t until = ticks() + count;
    const auto t0 = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(at_least);
    while (ticks() < until && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

 private:
  Executive& e_;
  std::uint64_t start_ = 0;
  std::atomic<std::uint64_t> allocations_{0};
  std::atomic<std::uint64_t> ticks_{0};
};

TEST(ExecutiveLoop, RunsAcrossAPackLargerThanItsBudgetWithoutFaultsOrAllocations) {
  const std::string path = build("executive_large", 385, 11);
  auto pack = storage::Pack::open(path);
  ASSERT_TRUE(pack.ok());
  storage::ResidentConfig rc;
  rc.budget_bytes = 4 * kMiB;
  rc.margin_m = 200;
  rc.poll_interval_s = 0.005;
  auto field = storage::ResidentPack::create(*pack, rc);
  ASSERT_TRUE(field.ok()) << field.status().message();
  ASSERT_GT((*field)->stats().pack_bytes, 6 * rc.budget_bytes);
  // nothing of the pack left in the page cache but what is locked
  {
    const int fd = ::open(path.c_str(), O_RDONLY);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::fdatasync(fd), 0);  // dirty pages cannot be dropped
    ASSERT_EQ(::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED), 0);
    ::close(fd);
  }
  ExecutiveConfig c;
  c.start_m = point_at(**field, 0.05, 0.05, 150);
  c.end_m = point_at(**field, 0.2, 0.15, 150);
  c.segments = 64;
  c.max_segments = 64;
  msg::CommandQueue commands;
  msg::AckQueue acks;
  LatestValue<msg::PathSample> paths;
  ExecutiveOutputs out;
  out.path = &paths;
  out.acks = &acks;
  auto sim = simulated(kPullScript, monotonic_ns());
  ASSERT_TRUE(sim);
  auto e = Executive::create(c, **field, &*sim->device, sim->sim.get(), &commands, out);
  ASSERT_TRUE(e.ok()) << e.status().message();

  (*field)->set_reader_active(true);
  (*field)->start_pager();
  CountingExecutive task(**e);
  PeriodicLoop loop(task);
  LoopConfig lc;
  lc.realtime.priority = 0;
  lc.realtime.lock_memory = false;
  lc.overrun_limit = 1000;  // a loaded test machine must not trip the safe state here
  ASSERT_TRUE(loop.start(lc).ok());
  // move the rope's ends across the pack, diagonal by diagonal
  for (int step = 1; step <= 12; ++step) {
    const double f = 0.05 + 0.7 * step / 12.0;
    msg::Command m{};
    m.kind = msg::CommandKind::set_endpoints;
    m.sequence = static_cast<std::uint64_t>(step);
    const Vec3 a = point_at(**field, f, f, 150), b = point_at(**field, f + 0.15, f + 0.1, 150);
    m.endpoints.start = {a.x(), a.y(), a.z()};
    m.endpoints.end = {b.x(), b.y(), b.z()};
    ASSERT_TRUE(commands.try_push(m));
    task.wait_ticks(60, std::chrono::milliseconds(150));
  }
  const LoopRun run = loop.stop();
  (*field)->set_reader_active(false);
  (*field)->stop_pager();
  const storage::ResidentStats s = (*field)->stats();
  EXPECT_GE(run.totals.ticks, 12u * 60u);
  // not even a minor fault once settled: every page a tick reads is locked and
  // mapped (a read of a brick that is not resident would fault, from the page
  // cache at best). Under AddressSanitizer the shadow of newly touched memory
  // is mapped lazily (tens of minor faults, and one that retries behind the
  // pager's munlock counts as major), so only the optimised build checks.
#ifndef VISVOL_SANITIZED
  EXPECT_EQ(run.totals.faults_after_settle.major, 0) << "the loop thread waited on the disk";
  EXPECT_EQ(run.totals.faults_after_settle.minor, 0);
#endif
  EXPECT_GT((*field)->fallbacks(), 0u) << "the rope should have outrun the pager somewhere";
  EXPECT_EQ(task.allocations(), 0u) << "the loop thread allocated";
  EXPECT_GT(s.bricks_evicted, 0u);
  EXPECT_LE(s.resident_bytes, s.budget_bytes);
  EXPECT_EQ((*e)->counters().commands_applied, 12u);
  field->reset();
  std::remove(path.c_str());
}

}  // namespace
}  // namespace visvol::rt
