// The executive and the haptic device tick by tick in simulated time: the
// operator's pull through the simulated device on its bus, what the executive
// makes of a device's reports, the safe state, and spool mode (the paper's
// mode B).
#include "executive_fixture.hpp"

namespace visvol::rt::executive_test {
namespace {

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

}  // namespace
}  // namespace visvol::rt::executive_test
