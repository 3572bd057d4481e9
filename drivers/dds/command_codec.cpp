#include "drivers/dds/command_codec.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include "base/tolerances.hpp"
#include "drivers/dds/message_codec.hpp"

namespace visvol::dds {
namespace {

static_assert(static_cast<int>(msg::CommandKind::set_endpoints) == visvol_msgs_msg_dds__COMMAND_SET_ENDPOINTS);
static_assert(static_cast<int>(msg::CommandKind::set_objective) == visvol_msgs_msg_dds__COMMAND_SET_OBJECTIVE);
static_assert(static_cast<int>(msg::CommandKind::set_weights) == visvol_msgs_msg_dds__COMMAND_SET_WEIGHTS);
static_assert(static_cast<int>(msg::CommandKind::set_stiffness) == visvol_msgs_msg_dds__COMMAND_SET_STIFFNESS);
static_assert(static_cast<int>(msg::CommandKind::set_model) == visvol_msgs_msg_dds__COMMAND_SET_MODEL);
static_assert(static_cast<int>(msg::CommandKind::set_segment_count) == visvol_msgs_msg_dds__COMMAND_SET_SEGMENT_COUNT);
static_assert(static_cast<int>(msg::CommandKind::set_constraints) == visvol_msgs_msg_dds__COMMAND_SET_CONSTRAINTS);
static_assert(static_cast<int>(msg::CommandKind::start) == visvol_msgs_msg_dds__COMMAND_START);
static_assert(static_cast<int>(msg::CommandKind::stop) == visvol_msgs_msg_dds__COMMAND_STOP);
static_assert(static_cast<int>(msg::CommandKind::switch_terrain) == visvol_msgs_msg_dds__COMMAND_SWITCH_TERRAIN);
static_assert(static_cast<int>(msg::CommandKind::set_mode) == visvol_msgs_msg_dds__COMMAND_SET_MODE);
static_assert(static_cast<int>(msg::InteractionMode::pull) == visvol_msgs_msg_dds__MODE_PULL);
static_assert(static_cast<int>(msg::InteractionMode::spool) == visvol_msgs_msg_dds__MODE_SPOOL);
static_assert(static_cast<int>(msg::RopeModel::spring_mass) == visvol_msgs_msg_dds__MODEL_SPRING_MASS);
static_assert(static_cast<int>(msg::RopeModel::articulated) == visvol_msgs_msg_dds__MODEL_ARTICULATED);
static_assert(static_cast<int>(msg::ConstraintKind::hidden_from) == visvol_msgs_msg_dds__CONSTRAINT_HIDDEN_FROM);
static_assert(static_cast<int>(msg::ConstraintKind::visible_to) == visvol_msgs_msg_dds__CONSTRAINT_VISIBLE_TO);
static_assert(static_cast<int>(msg::ConstraintKind::clearance) == visvol_msgs_msg_dds__CONSTRAINT_CLEARANCE);
static_assert(static_cast<int>(msg::ConstraintKind::max_agl) == visvol_msgs_msg_dds__CONSTRAINT_MAX_AGL);
static_assert(static_cast<int>(msg::ConstraintKind::max_altitude) == visvol_msgs_msg_dds__CONSTRAINT_MAX_ALTITUDE);
static_assert(static_cast<int>(msg::AckResult::accepted) == visvol_msgs_msg_dds__ACK_ACCEPTED);
static_assert(static_cast<int>(msg::AckResult::rejected) == visvol_msgs_msg_dds__ACK_REJECTED);
static_assert(static_cast<int>(msg::AckResult::applied) == visvol_msgs_msg_dds__ACK_APPLIED);
static_assert(static_cast<int>(msg::AckResult::failed) == visvol_msgs_msg_dds__ACK_FAILED);

constexpr std::uint8_t kLastKind = static_cast<std::uint8_t>(msg::CommandKind::set_mode);

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

Status reject(const std::string& field, const std::string& problem) { return invalid_argument(field + ": " + problem); }

// A received string: Cyclone never hands out null, a hand-made message might.
std::string_view view(const char* s) { return s ? std::string_view(s) : std::string_view(); }

bool printable(std::string_view s) {
  for (const char c : s) {
    if (c < 0x20 || c > 0x7e) return false;
  }
  return true;
}

Status check_finite(const std::string& field, double v) {
  if (!std::isfinite(v)) return reject(field, number(v) + " is not a finite number");
  return Status();
}

Status check_range(const std::string& field, double v, double lo, double hi, const char* unit) {
  VISVOL_RETURN_IF_ERROR(check_finite(field, v));
  if (v < lo || v > hi) {
    return reject(field, number(v) + " is outside [" + number(lo) + ", " + number(hi) + "]" + unit);
  }
  return Status();
}

// One coordinate of a point against [lo, hi] (finite, checked before):
// "FIELD.AXIS: V m is outside the pack's RANGE [LO, HI] m" and `why`.
Status check_axis(const std::string& field, const char* axis, double v, double lo, double hi, const std::string& range,
                  const char* why, double tol_m = 0) {
  if (!(v < lo - tol_m || v > hi + tol_m)) return Status();
  return reject(field + "." + axis,
                number(v) + " m is outside the pack's " + range + " [" + number(lo) + ", " + number(hi) + "] m" + why);
}

Status check_inside(const std::string& field, const msg::WorldPoint& p, const CommandLimits& limits) {
  VISVOL_RETURN_IF_ERROR(check_finite(field + ".x", p.x_m));
  VISVOL_RETURN_IF_ERROR(check_finite(field + ".y", p.y_m));
  VISVOL_RETURN_IF_ERROR(check_finite(field + ".z", p.z_m));
  VISVOL_RETURN_IF_ERROR(check_axis(field, "x", p.x_m, limits.min.x_m, limits.max.x_m, "x range", ""));
  VISVOL_RETURN_IF_ERROR(check_axis(field, "y", p.y_m, limits.min.y_m, limits.max.y_m, "y range", ""));
  return check_axis(field, "z", p.z_m, limits.min.z_m, limits.max.z_m, "z range", "");
}

bool has_planning_bounds(const CommandLimits& l) {
  return l.plan_min.x_m != 0 || l.plan_min.y_m != 0 || l.plan_max.x_m != 0 || l.plan_max.y_m != 0;
}

// An endpoint: inside the pack, and inside its planning bounds when set.
Status check_endpoint(const std::string& field, const msg::WorldPoint& p, const CommandLimits& limits) {
  VISVOL_RETURN_IF_ERROR(check_inside(field, p, limits));
  if (!has_planning_bounds(limits)) return Status();
  const char* why = " (where F_p counts every observer)";
  // to a centimetre, as the console's options, plan and check judge it
  VISVOL_RETURN_IF_ERROR(
      check_axis(field, "x", p.x_m, limits.plan_min.x_m, limits.plan_max.x_m, "planning bounds, x", why, kBoundsTolM));
  return check_axis(field, "y", p.y_m, limits.plan_min.y_m, limits.plan_max.y_m, "planning bounds, y", why,
                    kBoundsTolM);
}

msg::WorldPoint to_world(const geometry_msgs_msg_dds__Point_& p) { return msg::WorldPoint{p.x, p.y, p.z}; }

bool is_pack_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

Status decode_constraints(const visvol_msgs_msg_dds__Command_& wire, msg::Command& out) {
  const std::uint32_t n = wire.constraints._length;
  if (n > msg::kMaxConstraints) {
    return reject("constraints",
                  std::to_string(n) + " given, at most " + std::to_string(msg::kMaxConstraints) + " fit");
  }
  if (n > 0 && wire.constraints._buffer == nullptr) {
    return reject("constraints", "malformed sequence (no elements)");
  }
  out.constraints.count = n;
  for (std::uint32_t i = 0; i < n; ++i) {
    const visvol_msgs_msg_dds__Constraint_& c = wire.constraints._buffer[i];
    const std::string field = "constraints[" + std::to_string(i) + "]";
    if (c.kind < static_cast<std::uint8_t>(msg::ConstraintKind::hidden_from) ||
        c.kind > static_cast<std::uint8_t>(msg::ConstraintKind::max_altitude)) {
      return reject(field + ".kind", std::to_string(c.kind) +
                                         " is not a known constraint (1 hidden-from, "
                                         "2 visible-to, 3 clearance, 4 max-agl, 5 max-altitude)");
    }
    out.constraints.items[i] =
        msg::Constraint{static_cast<msg::ConstraintKind>(c.kind), to_world(c.position_m), c.height_m};
  }
  return Status();
}

// The most of each envelope kind in a command (one), and where it was.
struct EnvelopeItems {
  int clearance = -1, max_agl = -1, max_altitude = -1;  // item index, -1: absent
};

std::string item(std::uint32_t i) { return "constraints[" + std::to_string(i) + "]"; }

// One item's own values.
Status validate_item(const msg::Constraint& k, std::uint32_t i, const CommandLimits& limits) {
  const std::string height = item(i) + ".height_m";
  switch (k.kind) {
    case msg::ConstraintKind::hidden_from:
    case msg::ConstraintKind::visible_to: return check_inside(item(i) + ".position_m", k.position, limits);
    case msg::ConstraintKind::clearance: return check_range(height, k.height_m, 0.0, limits.max_clearance_m, " m");
    case msg::ConstraintKind::max_agl:
      VISVOL_RETURN_IF_ERROR(check_range(height, k.height_m, 0.0, limits.max_clearance_m, " m"));
      if (k.height_m == 0.0) return reject(height, "a max-agl of 0 m leaves no height to fly (> 0)");
      return Status();
    case msg::ConstraintKind::max_altitude:
      return check_range(height, k.height_m, limits.min.z_m, limits.max.z_m, " m (the pack's heights)");
  }
  return reject(item(i) + ".kind", "unknown");  // decode checked it
}

// Where item i's kind is an envelope limit: it must be the only one of its kind.
Status note_envelope_item(const msg::Constraint& k, std::uint32_t i, EnvelopeItems& seen) {
  int* slot = k.kind == msg::ConstraintKind::clearance      ? &seen.clearance
              : k.kind == msg::ConstraintKind::max_agl      ? &seen.max_agl
              : k.kind == msg::ConstraintKind::max_altitude ? &seen.max_altitude
                                                            : nullptr;
  if (slot == nullptr) return Status();
  if (*slot >= 0) {
    return reject(item(i) + ".kind", std::string("a second ") + to_string(k.kind) + " (the first is " +
                                         item(static_cast<std::uint32_t>(*slot)) + ")");
  }
  *slot = static_cast<int>(i);
  return Status();
}

Status validate_constraints(const msg::Command::Constraints& cs, const CommandLimits& limits) {
  if (cs.count > limits.max_constraints) {
    return reject("constraints",
                  std::to_string(cs.count) + " given, at most " + std::to_string(limits.max_constraints) + " reserved");
  }
  const std::uint32_t n = cs.count < msg::kMaxConstraints ? cs.count : static_cast<std::uint32_t>(msg::kMaxConstraints);
  EnvelopeItems seen;
  std::size_t hidden = 0, visible = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const msg::Constraint& k = cs.items[i];
    VISVOL_RETURN_IF_ERROR(validate_item(k, i, limits));
    VISVOL_RETURN_IF_ERROR(note_envelope_item(k, i, seen));
    hidden += k.kind == msg::ConstraintKind::hidden_from;
    visible += k.kind == msg::ConstraintKind::visible_to;
  }
  if (hidden > msg::kMaxObserversPerKind || visible > msg::kMaxObserversPerKind) {
    return reject("constraints", std::to_string(hidden) + " hidden-from and " + std::to_string(visible) +
                                     " visible-to points, at most " + std::to_string(msg::kMaxObserversPerKind) +
                                     " of a kind");
  }
  // one point both hidden from and visible to: no path meets both
  for (std::uint32_t i = 0; i < n; ++i) {
    const msg::Constraint& h = cs.items[i];
    if (h.kind != msg::ConstraintKind::hidden_from) continue;
    for (std::uint32_t j = 0; j < n; ++j) {
      const msg::Constraint& v = cs.items[j];
      if (v.kind == msg::ConstraintKind::visible_to &&
          same_point(h.position.x_m, h.position.y_m, h.position.z_m, v.position.x_m, v.position.y_m, v.position.z_m)) {
        return reject(item(j), "the point of " + item(i) + " too: no path is both hidden from it and in its sight");
      }
    }
  }
  if (hidden + visible > limits.max_observers) {
    return reject("constraints", std::to_string(hidden + visible) +
                                     " hidden-from and visible-to points, the console takes at most " +
                                     std::to_string(limits.max_observers));
  }
  if (seen.clearance >= 0 && seen.max_agl >= 0) {
    const double clearance = cs.items[seen.clearance].height_m, ceiling = cs.items[seen.max_agl].height_m;
    if (!(ceiling > clearance)) {
      return reject(item(static_cast<std::uint32_t>(seen.max_agl)) + ".height_m",
                    "max-agl " + number(ceiling) + " m is not above the clearance " + number(clearance) + " m of " +
                        item(static_cast<std::uint32_t>(seen.clearance)) + ": no height is allowed");
    }
  }
  return Status();
}

}  // namespace

Status check_source(std::string_view source) {
  if (source.empty()) return reject("source", "empty (name the sender)");
  if (source.size() >= msg::kSourceCapacity) {
    return reject("source",
                  std::to_string(source.size()) + " characters, at most " + std::to_string(msg::kSourceCapacity - 1));
  }
  if (!printable(source)) return reject("source", "holds characters outside printable ASCII");
  return Status();
}

Status check_pack_id(std::string_view field, std::string_view pack_id) {
  const std::string f(field);
  if (pack_id.empty()) return reject(f, "empty");
  if (pack_id.size() >= msg::kPackIdCapacity) {
    return reject(f,
                  std::to_string(pack_id.size()) + " characters, at most " + std::to_string(msg::kPackIdCapacity - 1));
  }
  for (const char c : pack_id) {
    if (!is_pack_char(c)) {
      return reject(f, "may hold only letters, digits, '.', '_' and '-'");
    }
  }
  return Status();
}

Status validate_limits(const CommandLimits& l) {
  const auto bad = [](const std::string& what) { return invalid_argument("command limits: " + what); };
  const double bounds[6] = {l.min.x_m, l.min.y_m, l.min.z_m, l.max.x_m, l.max.y_m, l.max.z_m};
  for (const double v : bounds) {
    if (!std::isfinite(v)) return bad("pack bounds are not finite");
  }
  if (!(l.min.x_m < l.max.x_m) || !(l.min.y_m < l.max.y_m) || !(l.min.z_m < l.max.z_m)) {
    return bad("pack bounds are empty (min must be below max on every axis)");
  }
  if (has_planning_bounds(l)) {
    const double plan[4] = {l.plan_min.x_m, l.plan_min.y_m, l.plan_max.x_m, l.plan_max.y_m};
    for (const double v : plan) {
      if (!std::isfinite(v)) return bad("planning bounds are not finite");
    }
    if (!(l.plan_min.x_m < l.plan_max.x_m && l.plan_min.y_m < l.plan_max.y_m && l.plan_min.x_m >= l.min.x_m &&
          l.plan_max.x_m <= l.max.x_m && l.plan_min.y_m >= l.min.y_m && l.plan_max.y_m <= l.max.y_m)) {
      return bad("planning bounds must be a non-empty box inside the pack bounds");
    }
  }
  if (l.min_segments < 1 || l.min_segments > l.max_segments) {
    return bad("segments: need 1 <= min_segments (" + std::to_string(l.min_segments) + ") <= max_segments (" +
               std::to_string(l.max_segments) + ")");
  }
  if (l.max_segments > msg::kMaxPathVertices - 1) {
    return bad("max_segments " + std::to_string(l.max_segments) + " above the " +
               std::to_string(msg::kMaxPathVertices - 1) + " a path sample holds");
  }
  if (l.max_observers > 2 * msg::kMaxObserversPerKind) {
    return bad("max_observers " + std::to_string(l.max_observers) + " above the " +
               std::to_string(2 * msg::kMaxObserversPerKind) + " a command holds");
  }
  if (l.max_constraints > msg::kMaxConstraints) {
    return bad("max_constraints " + std::to_string(l.max_constraints) + " above the " +
               std::to_string(msg::kMaxConstraints) + " a command holds");
  }
  const double maxima[4] = {l.max_weight, l.max_stretch_stiffness_n_per_m, l.max_bend_stiffness_n_m_per_rad,
                            l.max_clearance_m};
  for (const double v : maxima) {
    if (!std::isfinite(v) || !(v > 0.0)) return bad("every maximum must be finite and > 0");
  }
  if (l.pack_count > kMaxKnownPacks) {
    return bad("pack_count " + std::to_string(l.pack_count) + " above " + std::to_string(kMaxKnownPacks));
  }
  for (std::uint32_t i = 0; i < l.pack_count; ++i) {
    VISVOL_RETURN_IF_ERROR(
        check_pack_id("packs[" + std::to_string(i) + "]", msg::text_of(l.packs[i])).with_context("command limits"));
  }
  return Status();
}

Status add_known_pack(CommandLimits& limits, std::string_view pack_id) {
  VISVOL_RETURN_IF_ERROR(check_pack_id("pack id", pack_id));
  if (limits.pack_count >= kMaxKnownPacks) {
    return invalid_argument("command limits: more than " + std::to_string(kMaxKnownPacks) + " packs");
  }
  msg::copy_text(limits.packs[limits.pack_count++], pack_id);
  return Status();
}

Status decode_command(const visvol_msgs_msg_dds__Command_& wire, msg::Command& out) {
  out = msg::Command{};
  VISVOL_RETURN_IF_ERROR(check_source(view(wire.source)));
  msg::copy_text(out.source, view(wire.source));
  out.sequence = wire.sequence_number;
  if (wire.kind < 1 || wire.kind > kLastKind) {
    return reject("kind", std::to_string(wire.kind) + " is not a known command (1.." + std::to_string(kLastKind) + ")");
  }
  out.kind = static_cast<msg::CommandKind>(wire.kind);
  switch (out.kind) {
    case msg::CommandKind::set_endpoints:
      out.endpoints = msg::Command::Endpoints{to_world(wire.start_m), to_world(wire.end_m)};
      return Status();
    case msg::CommandKind::set_objective:
      if (wire.objective != static_cast<std::uint8_t>(msg::Objective::hide) &&
          wire.objective != static_cast<std::uint8_t>(msg::Objective::show)) {
        return reject("objective", std::to_string(wire.objective) + " is not known (1 hide, 2 show)");
      }
      out.objective = static_cast<msg::Objective>(wire.objective);
      return Status();
    case msg::CommandKind::set_weights:
      out.weights = msg::Weights{wire.k1_visibility, wire.k2_terrain, wire.k3_user, wire.k4_constraint};
      return Status();
    case msg::CommandKind::set_stiffness:
      out.stiffness = msg::Command::Stiffness{wire.stretch_stiffness_n_per_m, wire.bend_stiffness_n_m_per_rad};
      return Status();
    case msg::CommandKind::set_model:
      if (wire.model != static_cast<std::uint8_t>(msg::RopeModel::spring_mass) &&
          wire.model != static_cast<std::uint8_t>(msg::RopeModel::articulated)) {
        return reject("model", std::to_string(wire.model) + " is not known (1 spring-mass, 2 articulated)");
      }
      out.model = static_cast<msg::RopeModel>(wire.model);
      return Status();
    case msg::CommandKind::set_segment_count: out.segment_count = wire.segment_count; return Status();
    case msg::CommandKind::set_constraints: return decode_constraints(wire, out);
    case msg::CommandKind::start:
    case msg::CommandKind::stop: return Status();
    case msg::CommandKind::switch_terrain:
      VISVOL_RETURN_IF_ERROR(check_pack_id("pack_id", view(wire.pack_id)));
      msg::copy_text(out.pack_id, view(wire.pack_id));
      return Status();
    case msg::CommandKind::set_mode:
      if (wire.mode != static_cast<std::uint8_t>(msg::InteractionMode::pull) &&
          wire.mode != static_cast<std::uint8_t>(msg::InteractionMode::spool)) {
        return reject("mode", std::to_string(wire.mode) + " is not known (1 pull, 2 spool)");
      }
      out.mode = static_cast<msg::InteractionMode>(wire.mode);
      return Status();
  }
  return reject("kind", "unhandled");  // unreachable: the range was checked
}

Status validate_command(const msg::Command& c, const CommandLimits& limits) {
  switch (c.kind) {
    case msg::CommandKind::set_endpoints: {
      VISVOL_RETURN_IF_ERROR(check_endpoint("start_m", c.endpoints.start, limits));
      VISVOL_RETURN_IF_ERROR(check_endpoint("end_m", c.endpoints.end, limits));
      const msg::WorldPoint& a = c.endpoints.start;
      const msg::WorldPoint& b = c.endpoints.end;
      if (a.x_m == b.x_m && a.y_m == b.y_m && a.z_m == b.z_m) {
        return reject("end_m", "equals start_m (the rope needs two distinct ends)");
      }
      return Status();
    }
    case msg::CommandKind::set_weights:
      VISVOL_RETURN_IF_ERROR(check_range("k1_visibility", c.weights.k1_visibility, 0.0, limits.max_weight, ""));
      VISVOL_RETURN_IF_ERROR(check_range("k2_terrain", c.weights.k2_terrain, 0.0, limits.max_weight, ""));
      VISVOL_RETURN_IF_ERROR(check_range("k3_user", c.weights.k3_user, 0.0, limits.max_weight, ""));
      return check_range("k4_constraint", c.weights.k4_constraint, 0.0, limits.max_weight, "");
    case msg::CommandKind::set_stiffness:
      VISVOL_RETURN_IF_ERROR(check_range("stretch_stiffness_n_per_m", c.stiffness.stretch_n_per_m, 0.0,
                                         limits.max_stretch_stiffness_n_per_m, " N/m"));
      if (c.stiffness.stretch_n_per_m == 0.0) {
        return reject("stretch_stiffness_n_per_m", "0 N/m would let the rope fall apart (> 0)");
      }
      return check_range("bend_stiffness_n_m_per_rad", c.stiffness.bend_n_m_per_rad, 0.0,
                         limits.max_bend_stiffness_n_m_per_rad, " N m/rad");
    case msg::CommandKind::set_segment_count:
      if (c.segment_count < limits.min_segments || c.segment_count > limits.max_segments) {
        return reject("segment_count", std::to_string(c.segment_count) + " is outside the " +
                                           std::to_string(limits.min_segments) + ".." +
                                           std::to_string(limits.max_segments) + " segments reserved");
      }
      return Status();
    case msg::CommandKind::set_constraints: return validate_constraints(c.constraints, limits);
    case msg::CommandKind::switch_terrain: {
      const std::string_view id = msg::text_of(c.pack_id);
      if (limits.pack_count == 0) {
        return reject("pack_id", "'" + std::string(id) + "': this console has no other packs");
      }
      for (std::uint32_t i = 0; i < limits.pack_count && i < kMaxKnownPacks; ++i) {
        if (msg::text_of(limits.packs[i]) == id) return Status();
      }
      return reject("pack_id", "'" + std::string(id) + "' is not a pack on this console");
    }
    case msg::CommandKind::set_objective:
    case msg::CommandKind::set_model:
    case msg::CommandKind::set_mode:
    case msg::CommandKind::start:
    case msg::CommandKind::stop: return Status();  // decode checked their values
  }
  return reject("kind", std::to_string(static_cast<int>(c.kind)) + " is not a known command");
}

Status decode_and_validate(const visvol_msgs_msg_dds__Command_& wire, const CommandLimits& limits, msg::Command& out) {
  VISVOL_RETURN_IF_ERROR(decode_command(wire, out));
  return validate_command(out, limits);
}

// Sender side ------------------------------------------------------------------

const visvol_msgs_msg_dds__Command_& CommandMessage::fill(const msg::Command& c) {
  msg_ = visvol_msgs_msg_dds__Command_{};
  msg::copy_text(source_, msg::text_of(c.source));
  msg::copy_text(pack_id_, msg::text_of(c.pack_id));
  msg_.source = source_;
  msg_.pack_id = pack_id_;
  msg_.sequence_number = c.sequence;
  msg_.kind = static_cast<std::uint8_t>(c.kind);
  msg_.start_m = {c.endpoints.start.x_m, c.endpoints.start.y_m, c.endpoints.start.z_m};
  msg_.end_m = {c.endpoints.end.x_m, c.endpoints.end.y_m, c.endpoints.end.z_m};
  msg_.objective = static_cast<std::uint8_t>(c.objective);
  msg_.k1_visibility = c.weights.k1_visibility;
  msg_.k2_terrain = c.weights.k2_terrain;
  msg_.k3_user = c.weights.k3_user;
  msg_.k4_constraint = c.weights.k4_constraint;
  msg_.stretch_stiffness_n_per_m = c.stiffness.stretch_n_per_m;
  msg_.bend_stiffness_n_m_per_rad = c.stiffness.bend_n_m_per_rad;
  msg_.model = static_cast<std::uint8_t>(c.model);
  msg_.segment_count = c.segment_count;
  msg_.mode = static_cast<std::uint8_t>(c.mode);
  const std::uint32_t n = c.constraints.count < msg::kMaxConstraints ? c.constraints.count
                                                                     : static_cast<std::uint32_t>(msg::kMaxConstraints);
  for (std::uint32_t i = 0; i < n; ++i) {
    const msg::Constraint& k = c.constraints.items[i];
    constraints_[i] = visvol_msgs_msg_dds__Constraint_{
        static_cast<std::uint8_t>(k.kind), {k.position.x_m, k.position.y_m, k.position.z_m}, k.height_m};
  }
  msg_.constraints._buffer = constraints_;
  msg_.constraints._length = n;
  msg_.constraints._maximum = static_cast<std::uint32_t>(msg::kMaxConstraints);
  msg_.constraints._release = false;
  return msg_;
}

AckMessage::AckMessage(std::string frame_id) : frame_id_(std::move(frame_id)) {
  msg_.header.frame_id = frame_id_.data();
  msg_.source = source_;
  msg_.reason = reason_;
}

const visvol_msgs_msg_dds__CommandAck_& AckMessage::fill(const msg::CommandAck& ack) {
  msg_.header.stamp = to_ros_time(msg::now_stamp_ns());
  msg::copy_text(source_, msg::text_of(ack.source));
  msg::copy_text(reason_, msg::text_of(ack.reason));
  msg_.sequence_number = ack.sequence;
  msg_.kind = ack.kind;
  msg_.result = static_cast<std::uint8_t>(ack.result);
  return msg_;
}

msg::CommandAck decode_ack(const visvol_msgs_msg_dds__CommandAck_& wire) {
  msg::CommandAck ack{};
  msg::copy_text(ack.source, view(wire.source));
  msg::copy_text(ack.reason, view(wire.reason));
  ack.sequence = wire.sequence_number;
  ack.kind = wire.kind;
  ack.result = static_cast<msg::AckResult>(wire.result);
  return ack;
}

}  // namespace visvol::dds
