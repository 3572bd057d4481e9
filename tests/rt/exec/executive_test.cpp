// The executive tick by tick in simulated time (deterministic): endpoints,
// the rope settling and handed off, rebuilds, a rope that stops being finite,
// the ceiling, no allocation; and once on the real periodic loop across a pack
// much larger than its tile budget.
#include "executive_fixture.hpp"

namespace visvol::rt::executive_test {
namespace {

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
  // its size is what matters here (the pager's budget); a range of 2 posts
  // builds it in a fraction of the time of 8 (the suite's longest test
  // under ThreadSanitizer)
  const std::string path = build("executive_large", 385, 11, 2);
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
}  // namespace visvol::rt::executive_test
