// Command decoding and validation, without DDS.
#include "drivers/dds/command_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace visvol::dds {
namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

CommandLimits limits() {
  CommandLimits l;
  l.min = {0.0, 0.0, 0.0};
  l.max = {1000.0, 2000.0, 500.0};
  l.max_segments = 100;
  l.max_constraints = 3;
  l.max_weight = 10.0;
  l.max_stretch_stiffness_n_per_m = 5000.0;
  l.max_bend_stiffness_n_m_per_rad = 50.0;
  l.max_clearance_m = 300.0;
  EXPECT_TRUE(add_known_pack(l, "sf_north").ok());
  return l;
}

// A message as a sender would write it, with its own storage.
struct Msg {
  visvol_msgs_msg_dds__Command_ m{};
  std::string source = "op";
  std::string pack = "";
  visvol_msgs_msg_dds__Constraint_ constraints[msg::kMaxConstraints + 1] = {};
  explicit Msg(std::uint8_t kind) {
    m.kind = kind;
    m.sequence_number = 42;
    sync();
  }
  void sync() {
    m.source = source.data();
    m.pack_id = pack.data();
    m.constraints._buffer = constraints;
  }
};

// The reason decode_and_validate gives, or "" when it accepts.
std::string verdict(Msg& msg, const CommandLimits& l = limits()) {
  msg.sync();
  msg::Command out{};
  const Status s = decode_and_validate(msg.m, l, out);
  if (!s.ok()) {
    EXPECT_EQ(s.code(), Errc::invalid_argument);
  }
  return s.ok() ? std::string() : s.message();
}

constexpr std::uint8_t kind(msg::CommandKind k) { return static_cast<std::uint8_t>(k); }

TEST(DecodeCommand, EachKindDecodesItsFields) {
  msg::Command out{};
  Msg e(kind(msg::CommandKind::set_endpoints));
  e.m.start_m = {1.0, 2.0, 3.0};
  e.m.end_m = {4.0, 5.0, 6.0};
  e.m.k1_visibility = 99.0;  // not of this kind: ignored
  e.sync();
  ASSERT_TRUE(decode_and_validate(e.m, limits(), out).ok());
  EXPECT_EQ(out.kind, msg::CommandKind::set_endpoints);
  EXPECT_EQ(out.sequence, 42u);
  EXPECT_EQ(msg::text_of(out.source), "op");
  EXPECT_EQ(out.endpoints.start.y_m, 2.0);
  EXPECT_EQ(out.endpoints.end.z_m, 6.0);
  EXPECT_EQ(out.weights.k1_visibility, 0.0);

  Msg w(kind(msg::CommandKind::set_weights));
  w.m.k1_visibility = 1.0;
  w.m.k2_terrain = 2.0;
  w.m.k3_user = 3.0;
  w.m.k4_constraint = 4.0;
  w.sync();
  ASSERT_TRUE(decode_and_validate(w.m, limits(), out).ok());
  EXPECT_EQ(out.weights.k4_constraint, 4.0);

  Msg s(kind(msg::CommandKind::set_stiffness));
  s.m.stretch_stiffness_n_per_m = 800.0;
  s.m.bend_stiffness_n_m_per_rad = 0.0;
  s.sync();
  ASSERT_TRUE(decode_and_validate(s.m, limits(), out).ok());
  EXPECT_EQ(out.stiffness.stretch_n_per_m, 800.0);

  Msg md(kind(msg::CommandKind::set_model));
  md.m.model = 2;
  md.sync();
  ASSERT_TRUE(decode_and_validate(md.m, limits(), out).ok());
  EXPECT_EQ(out.model, msg::RopeModel::articulated);

  Msg n(kind(msg::CommandKind::set_segment_count));
  n.m.segment_count = 100;
  n.sync();
  ASSERT_TRUE(decode_and_validate(n.m, limits(), out).ok());
  EXPECT_EQ(out.segment_count, 100u);

  Msg c(kind(msg::CommandKind::set_constraints));
  c.constraints[0] = {1, {10.0, 20.0, 30.0}, 0.0};
  c.constraints[1] = {3, {}, 150.0};
  c.m.constraints._length = 2;
  c.sync();
  ASSERT_TRUE(decode_and_validate(c.m, limits(), out).ok());
  ASSERT_EQ(out.constraints.count, 2u);
  EXPECT_EQ(out.constraints.items[0].kind, msg::ConstraintKind::hidden_from);
  EXPECT_EQ(out.constraints.items[0].position.z_m, 30.0);
  EXPECT_EQ(out.constraints.items[1].height_m, 150.0);

  // every kind at once: observers of both kinds, clearance and both ceilings
  Msg all(kind(msg::CommandKind::set_constraints));
  all.constraints[0] = {1, {10.0, 20.0, 30.0}, 0.0};
  all.constraints[1] = {2, {15.0, 25.0, 35.0}, 0.0};
  all.constraints[2] = {3, {}, 40.0};
  all.constraints[3] = {4, {}, 120.0};
  all.constraints[4] = {5, {}, 450.0};
  all.m.constraints._length = 5;
  all.sync();
  CommandLimits five = limits();
  five.max_constraints = 5;
  ASSERT_TRUE(decode_and_validate(all.m, five, out).ok());
  ASSERT_EQ(out.constraints.count, 5u);
  EXPECT_EQ(out.constraints.items[3].kind, msg::ConstraintKind::max_agl);
  EXPECT_EQ(out.constraints.items[3].height_m, 120.0);
  EXPECT_EQ(out.constraints.items[4].kind, msg::ConstraintKind::max_altitude);
  EXPECT_EQ(out.constraints.items[4].height_m, 450.0);
  EXPECT_STREQ(to_string(msg::ConstraintKind::max_agl), "max-agl");
  EXPECT_STREQ(to_string(msg::ConstraintKind::max_altitude), "max-altitude");

  Msg empty(kind(msg::CommandKind::set_constraints));  // clears the set
  EXPECT_EQ(verdict(empty), "");

  Msg t(kind(msg::CommandKind::switch_terrain));
  t.pack = "sf_north";
  t.sync();
  ASSERT_TRUE(decode_and_validate(t.m, limits(), out).ok());
  EXPECT_EQ(msg::text_of(out.pack_id), "sf_north");

  for (const msg::CommandKind k : {msg::CommandKind::start, msg::CommandKind::stop}) {
    Msg m(kind(k));
    EXPECT_EQ(verdict(m), "");
  }
  Msg o(kind(msg::CommandKind::set_objective));
  o.m.objective = 1;
  EXPECT_EQ(verdict(o), "");
  for (const msg::InteractionMode mode : {msg::InteractionMode::pull, msg::InteractionMode::spool}) {
    Msg sm(kind(msg::CommandKind::set_mode));
    sm.m.mode = static_cast<std::uint8_t>(mode);
    ASSERT_EQ(verdict(sm), "");
    msg::Command decoded{};
    ASSERT_TRUE(decode_and_validate(sm.m, limits(), decoded).ok());
    EXPECT_EQ(decoded.mode, mode);
  }
}

TEST(DecodeCommand, StructuralProblemsNameTheField) {
  Msg k(0);
  EXPECT_EQ(verdict(k), "kind: 0 is not a known command (1..11)");
  Msg k2(12);
  EXPECT_EQ(verdict(k2), "kind: 12 is not a known command (1..11)");

  Msg s(kind(msg::CommandKind::start));
  s.source = "";
  EXPECT_EQ(verdict(s), "source: empty (name the sender)");
  s.source = std::string(64, 'a');
  EXPECT_EQ(verdict(s), "source: 64 characters, at most 63");
  s.source = "tab\there";
  EXPECT_EQ(verdict(s), "source: holds characters outside printable ASCII");
  Msg null_source(kind(msg::CommandKind::start));
  null_source.m.source = nullptr;  // a hand-made message, not from Cyclone
  msg::Command out{};
  EXPECT_FALSE(decode_command(null_source.m, out).ok());

  Msg o(kind(msg::CommandKind::set_objective));
  o.m.objective = 0;
  EXPECT_EQ(verdict(o), "objective: 0 is not known (1 hide, 2 show)");
  Msg md(kind(msg::CommandKind::set_model));
  md.m.model = 3;
  EXPECT_EQ(verdict(md), "model: 3 is not known (1 spring-mass, 2 articulated)");

  Msg c(kind(msg::CommandKind::set_constraints));
  c.m.constraints._length = msg::kMaxConstraints + 1;
  EXPECT_EQ(verdict(c), "constraints: 516 given, at most 515 fit");
  c.m.constraints._length = 2;
  c.constraints[0] = {3, {}, 10.0};
  c.constraints[1] = {6, {}, 10.0};
  EXPECT_EQ(verdict(c),
            "constraints[1].kind: 6 is not a known constraint (1 hidden-from, 2 visible-to, "
            "3 clearance, 4 max-agl, 5 max-altitude)");
  Msg hollow(kind(msg::CommandKind::set_constraints));
  hollow.sync();
  hollow.m.constraints._length = 1;
  hollow.m.constraints._buffer = nullptr;
  EXPECT_FALSE(decode_command(hollow.m, out).ok());

  Msg t(kind(msg::CommandKind::switch_terrain));
  t.pack = "";
  EXPECT_EQ(verdict(t), "pack_id: empty");
  t.pack = "../etc/passwd";
  EXPECT_EQ(verdict(t), "pack_id: may hold only letters, digits, '.', '_' and '-'");
  t.pack = std::string(70, 'p');
  EXPECT_EQ(verdict(t), "pack_id: 70 characters, at most 63");
}

TEST(ValidateCommand, ValuesAreCheckedAgainstTheLimits) {
  Msg e(kind(msg::CommandKind::set_endpoints));
  e.m.start_m = {1.0, 2.0, 3.0};
  e.m.end_m = {4.0, 5.0, 6.0};
  e.m.start_m.y = kInf;
  EXPECT_EQ(verdict(e), "start_m.y: inf is not a finite number");
  e.m.start_m.y = 2.0;
  e.m.end_m.z = kNan;
  EXPECT_EQ(verdict(e), "end_m.z: nan is not a finite number");
  e.m.end_m.z = 501.0;
  EXPECT_EQ(verdict(e), "end_m.z: 501 m is outside the pack's z range [0, 500] m");
  e.m.end_m.z = 6.0;
  e.m.start_m.x = -0.5;
  EXPECT_EQ(verdict(e), "start_m.x: -0.5 m is outside the pack's x range [0, 1000] m");
  e.m.start_m = e.m.end_m;
  EXPECT_EQ(verdict(e), "end_m: equals start_m (the rope needs two distinct ends)");
  e.m.start_m = {0.0, 0.0, 0.0};  // the bounds are inclusive
  e.m.end_m = {1000.0, 2000.0, 500.0};
  EXPECT_EQ(verdict(e), "");

  Msg w(kind(msg::CommandKind::set_weights));
  w.m.k3_user = 10.5;
  EXPECT_EQ(verdict(w), "k3_user: 10.5 is outside [0, 10]");
  w.m.k3_user = 0.0;
  w.m.k1_visibility = -kInf;
  EXPECT_EQ(verdict(w), "k1_visibility: -inf is not a finite number");

  Msg s(kind(msg::CommandKind::set_stiffness));
  s.m.stretch_stiffness_n_per_m = 0.0;
  EXPECT_EQ(verdict(s), "stretch_stiffness_n_per_m: 0 N/m would let the rope fall apart (> 0)");
  s.m.stretch_stiffness_n_per_m = 6000.0;
  EXPECT_EQ(verdict(s), "stretch_stiffness_n_per_m: 6000 is outside [0, 5000] N/m");
  s.m.stretch_stiffness_n_per_m = 100.0;
  s.m.bend_stiffness_n_m_per_rad = -1.0;
  EXPECT_EQ(verdict(s), "bend_stiffness_n_m_per_rad: -1 is outside [0, 50] N m/rad");

  Msg n(kind(msg::CommandKind::set_segment_count));
  n.m.segment_count = 1;
  EXPECT_EQ(verdict(n), "segment_count: 1 is outside the 2..100 segments reserved");
  n.m.segment_count = 101;
  EXPECT_EQ(verdict(n), "segment_count: 101 is outside the 2..100 segments reserved");

  Msg c(kind(msg::CommandKind::set_constraints));
  c.m.constraints._length = 4;
  for (int i = 0; i < 4; ++i) c.constraints[i] = {3, {}, 10.0};
  EXPECT_EQ(verdict(c), "constraints: 4 given, at most 3 reserved");
  c.m.constraints._length = 2;
  c.constraints[1] = {2, {10.0, 3000.0, 5.0}, 0.0};
  EXPECT_EQ(verdict(c), "constraints[1].position_m.y: 3000 m is outside the pack's y range [0, 2000] m");
  c.constraints[1] = {3, {}, 301.0};
  EXPECT_EQ(verdict(c), "constraints[1].height_m: 301 is outside [0, 300] m");
  c.constraints[0] = {1, {10.0, 20.0, 30.0}, 0.0};
  c.constraints[1] = {3, {kNan, kNan, kNan}, 20.0};  // clearance ignores position
  EXPECT_EQ(verdict(c), "");
  // one point hidden from and visible to: no path meets both
  c.constraints[1] = {2, {10.0, 20.0, 30.0}, 0.0};
  EXPECT_EQ(verdict(c),
            "constraints[1]: the point of constraints[0] too: no path is both hidden from it and in its sight");
  c.constraints[1] = {2, {10.0, 20.0, 31.0}, 0.0};
  EXPECT_EQ(verdict(c), "");

  Msg t(kind(msg::CommandKind::switch_terrain));
  t.pack = "taunus";
  EXPECT_EQ(verdict(t), "pack_id: 'taunus' is not a pack on this console");
  CommandLimits none = limits();
  none.pack_count = 0;
  EXPECT_EQ(verdict(t, none), "pack_id: 'taunus': this console has no other packs");
}

// Endpoints inside the planning bounds; observers anywhere on the pack.
TEST(ValidateCommand, EndpointsStayInsideThePlanningBoundsObserversNeedNot) {
  CommandLimits l = limits();
  l.plan_min = {100.0, 200.0, 0.0};
  l.plan_max = {900.0, 1800.0, 0.0};
  ASSERT_TRUE(validate_limits(l).ok());
  msg::Command c{};
  c.kind = msg::CommandKind::set_endpoints;
  c.endpoints.start = {50.0, 1000.0, 100.0};
  c.endpoints.end = {500.0, 1000.0, 100.0};
  EXPECT_EQ(validate_command(c, l).message(),
            "start_m.x: 50 m is outside the pack's planning bounds, x [100, 900] m (where F_p counts every observer)");
  c.endpoints.start.x_m = 99.995;  // within the centimetre the bounds are judged to (base/tolerances.hpp)
  EXPECT_TRUE(validate_command(c, l).ok()) << validate_command(c, l).message();
  c.endpoints.start.x_m = 99.98;
  EXPECT_EQ(
      validate_command(c, l).message(),
      "start_m.x: 99.98 m is outside the pack's planning bounds, x [100, 900] m (where F_p counts every observer)");
  c.endpoints.start.x_m = 100.0;  // inclusive
  c.endpoints.end.y_m = 1900.0;
  EXPECT_NE(validate_command(c, l).message().find("end_m.y: 1900 m is outside the pack's planning bounds"),
            std::string::npos);
  c.endpoints.end.y_m = 1800.0;
  EXPECT_TRUE(validate_command(c, l).ok()) << validate_command(c, l).message();
  msg::Command k{};
  k.kind = msg::CommandKind::set_constraints;
  k.constraints.count = 1;
  k.constraints.items[0] = {
      msg::ConstraintKind::hidden_from, {50.0, 1950.0, 20.0}, 0.0};  // beyond the bounds, on the pack
  EXPECT_TRUE(validate_command(k, l).ok()) << validate_command(k, l).message();
  l.plan_max.x_m = 1500.0;  // beyond the pack
  EXPECT_NE(validate_limits(l).message().find("inside the pack bounds"), std::string::npos);
}

// The ceiling: a finite height, above 0 and above the clearance given with
// it (max-agl), inside the pack's heights (max-altitude); one of each kind.
TEST(ValidateCommand, CeilingsAreCheckedWithAReason) {
  Msg c(kind(msg::CommandKind::set_constraints));
  c.m.constraints._length = 1;
  const std::pair<visvol_msgs_msg_dds__Constraint_, const char*> cases[] = {
      {{4, {}, kNan}, "constraints[0].height_m: nan is not a finite number"},
      {{4, {}, kInf}, "constraints[0].height_m: inf is not a finite number"},
      {{4, {}, -5.0}, "constraints[0].height_m: -5 is outside [0, 300] m"},
      {{4, {}, 0.0}, "constraints[0].height_m: a max-agl of 0 m leaves no height to fly (> 0)"},
      {{4, {}, 301.0}, "constraints[0].height_m: 301 is outside [0, 300] m"},
      {{5, {}, -kInf}, "constraints[0].height_m: -inf is not a finite number"},
      {{5, {}, -1.0}, "constraints[0].height_m: -1 is outside [0, 500] m (the pack's heights)"},
      {{5, {}, 501.0}, "constraints[0].height_m: 501 is outside [0, 500] m (the pack's heights)"},
      {{3, {}, -0.5}, "constraints[0].height_m: -0.5 is outside [0, 300] m"},
  };
  for (const auto& [constraint, reason] : cases) {
    c.constraints[0] = constraint;
    EXPECT_EQ(verdict(c), reason);
  }
  c.constraints[0] = {4, {}, 250.0};
  EXPECT_EQ(verdict(c), "");
  c.constraints[0] = {5, {}, 500.0};
  EXPECT_EQ(verdict(c), "");

  // with the clearance of the same command
  c.m.constraints._length = 2;
  c.constraints[0] = {3, {}, 50.0};
  c.constraints[1] = {4, {}, 40.0};
  EXPECT_EQ(verdict(c),
            "constraints[1].height_m: max-agl 40 m is not above the clearance 50 m of constraints[0]: "
            "no height is allowed");
  c.constraints[1] = {4, {}, 50.0};
  EXPECT_NE(verdict(c).find("is not above the clearance"), std::string::npos);
  c.constraints[1] = {4, {}, 50.5};
  EXPECT_EQ(verdict(c), "");
  // twice the same limit
  c.constraints[1] = {3, {}, 60.0};
  EXPECT_EQ(verdict(c), "constraints[1].kind: a second clearance (the first is constraints[0])");
  c.constraints[0] = {5, {}, 100.0};
  c.constraints[1] = {5, {}, 200.0};
  EXPECT_EQ(verdict(c), "constraints[1].kind: a second max-altitude (the first is constraints[0])");
}

// Observers: up to kMaxObserversPerKind of each kind, no more than the
// console takes (--max-observers).
TEST(ValidateCommand, ObserversFitWhatTheConsoleTakes) {
  CommandLimits l = limits();
  l.max_constraints = static_cast<std::uint32_t>(msg::kMaxConstraints);
  Msg c(kind(msg::CommandKind::set_constraints));
  const auto per_kind = static_cast<std::uint32_t>(msg::kMaxObserversPerKind);
  for (std::uint32_t i = 0; i < per_kind; ++i) {
    c.constraints[i] = {1, {10.0 + i, 20.0, 30.0}, 0.0};
    c.constraints[per_kind + i] = {2, {20.0, 10.0 + i, 40.0}, 0.0};
  }
  c.m.constraints._length = 2 * per_kind;
  EXPECT_EQ(verdict(c, l), "") << "256 of each kind";
  c.constraints[2 * per_kind - 1] = {1, {1.0, 1.0, 1.0}, 0.0};
  EXPECT_EQ(verdict(c, l), "constraints: 257 hidden-from and 255 visible-to points, at most 256 of a kind");
  c.constraints[2 * per_kind - 1] = {2, {1.0, 1.0, 1.0}, 0.0};
  l.max_observers = 12;
  EXPECT_EQ(verdict(c, l), "constraints: 512 hidden-from and visible-to points, the console takes at most 12");
  c.m.constraints._length = 12;
  EXPECT_EQ(verdict(c, l), "");
  l.max_observers = 0;
  c.m.constraints._length = 1;
  EXPECT_NE(verdict(c, l).find("the console takes at most 0"), std::string::npos);
  c.constraints[0] = {4, {}, 100.0};  // no observer: none needed
  EXPECT_EQ(verdict(c, l), "");
  l.max_observers = 2 * msg::kMaxObserversPerKind + 1;
  EXPECT_NE(validate_limits(l).message().find("max_observers"), std::string::npos);
}

TEST(CommandLimits, ValidationSaysWhatIsWrong) {
  EXPECT_TRUE(validate_limits(limits()).ok());
  CommandLimits l = limits();
  l.min.z_m = kNan;
  EXPECT_EQ(validate_limits(l).message(), "command limits: pack bounds are not finite");
  l = limits();
  l.max.y_m = l.min.y_m;
  EXPECT_NE(validate_limits(l).message().find("pack bounds are empty"), std::string::npos);
  l = limits();
  l.max_segments = static_cast<std::uint32_t>(msg::kMaxPathVertices);
  EXPECT_NE(validate_limits(l).message().find("a path sample holds"), std::string::npos);
  l = limits();
  l.min_segments = 0;
  EXPECT_FALSE(validate_limits(l).ok());
  l = limits();
  l.max_constraints = msg::kMaxConstraints + 1;
  EXPECT_FALSE(validate_limits(l).ok());
  l = limits();
  l.max_weight = 0.0;
  EXPECT_FALSE(validate_limits(l).ok());
  l = limits();
  l.pack_count = kMaxKnownPacks + 1;
  EXPECT_FALSE(validate_limits(l).ok());
  l = limits();
  msg::copy_text(l.packs[0], "bad pack");
  EXPECT_NE(validate_limits(l).message().find("packs[0]"), std::string::npos);
  l = limits();
  EXPECT_FALSE(add_known_pack(l, "no/slash").ok());
  for (std::size_t i = l.pack_count; i < kMaxKnownPacks; ++i) {
    ASSERT_TRUE(add_known_pack(l, "p" + std::to_string(i)).ok());
  }
  EXPECT_FALSE(add_known_pack(l, "one_more").ok());
}

TEST(CommandMessage, EncodeThenDecodeGivesTheCommandBack) {
  msg::Command c{};
  c.kind = msg::CommandKind::set_constraints;
  c.sequence = 77;
  msg::copy_text(c.source, "planner-2");
  c.constraints.count = 3;
  c.constraints.items[0] = {msg::ConstraintKind::visible_to, {1.0, 2.0, 3.0}, 0.0};
  c.constraints.items[1] = {msg::ConstraintKind::clearance, {}, 40.0};
  c.constraints.items[2] = {msg::ConstraintKind::max_agl, {}, 90.0};
  CommandMessage m;
  msg::Command back{};
  ASSERT_TRUE(decode_and_validate(m.fill(c), limits(), back).ok());
  EXPECT_EQ(back.sequence, 77u);
  EXPECT_EQ(msg::text_of(back.source), "planner-2");
  ASSERT_EQ(back.constraints.count, 3u);
  EXPECT_EQ(back.constraints.items[0].kind, msg::ConstraintKind::visible_to);
  EXPECT_EQ(back.constraints.items[0].position.y_m, 2.0);
  EXPECT_EQ(back.constraints.items[1].height_m, 40.0);
  EXPECT_EQ(back.constraints.items[2].kind, msg::ConstraintKind::max_agl);
  EXPECT_EQ(back.constraints.items[2].height_m, 90.0);
}

TEST(AckMessage, CarriesSourceSequenceAndReason) {
  msg::CommandAck ack{};
  msg::copy_text(ack.source, "op");
  ack.sequence = 5;
  ack.kind = 77;
  ack.result = msg::AckResult::rejected;
  msg::copy_text(ack.reason, "kind: 77 is not a known command (1..11)");
  AckMessage m("visvol_world");
  const visvol_msgs_msg_dds__CommandAck_& msg = m.fill(ack);
  EXPECT_STREQ(msg.header.frame_id, "visvol_world");
  EXPECT_GT(msg.header.stamp.sec, 1600000000);
  const msg::CommandAck back = decode_ack(msg);
  EXPECT_EQ(msg::text_of(back.source), "op");
  EXPECT_EQ(back.sequence, 5u);
  EXPECT_EQ(back.kind, 77);
  EXPECT_EQ(back.result, msg::AckResult::rejected);
  EXPECT_STREQ(back.reason, ack.reason);
}

}  // namespace
}  // namespace visvol::dds
