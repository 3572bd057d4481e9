// The executive's commands tick by tick in simulated time: applied or failed
// with a reason, large constraint sets spread over ticks, observers' hulls
// coming into force beside the loop, a terrain switch handed to the console.
#include "executive_fixture.hpp"

namespace visvol::rt::executive_test {
namespace {

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

}  // namespace
}  // namespace visvol::rt::executive_test
