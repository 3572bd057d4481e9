// The executive's command applier: operator commands taken from the queue, checked, applied and acknowledged.
// Loop thread (real-time rules: no allocation, no lock, no logging, no blocking), except check_observers() and
// check_ceiling(), which init() runs on the configuration, and terrain_switch(), which any thread may ask.
#include "rt/exec/executive.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "base/tolerances.hpp"
#include "rt/exec/executive_detail.hpp"
#include "rt/rope/planner.hpp"

namespace visvol::rt {

using detail::check_point;
using detail::inside;

namespace {

static_assert(kMaxPlanObservers == kMaxObserversPerKind, "the console takes as many observers as the planner");
static_assert(msg::kMaxObserversPerKind == static_cast<std::size_t>(kMaxObserversPerKind),
              "a command's observers of a kind are what a hull request holds");

// A command whose springs or gains the loop's fixed step could not integrate
// (the rope would diverge within ticks): refused, nothing changed.
constexpr const char* kUnstable =
    "the rope would step outside its stability margin at the loop's period with these springs, gains and "
    "margins (lower the stiffness or the weights, or widen the clearance)";
constexpr const char* kSpooling = "the rope is being spooled out: switch to pull mode first (set-mode pull)";

}  // namespace

// The work a command makes the loop do, in items: a set-constraints command's
// constraints (up to msg::kMaxConstraints); a command that lays the rope
// again (start, set-endpoints, set-segments, set-model), its vertices (at
// most kMaxConstraints: a rope of more takes a tick of its own); one for any
// other command.
int Executive::command_items(const msg::Command& c) const {
  auto bounded = [](std::int64_t n) { return static_cast<int>(std::clamp<std::int64_t>(n, 1, msg::kMaxConstraints)); };
  switch (c.kind) {
    case msg::CommandKind::set_constraints: return bounded(c.constraints.count);
    case msg::CommandKind::set_segment_count: return bounded(std::int64_t{c.segment_count} + 1);
    case msg::CommandKind::start:
    case msg::CommandKind::set_endpoints:
    case msg::CommandKind::set_mode:  // a spool's rope is short, the pull mode's laid again is not
    case msg::CommandKind::set_model: return bounded(std::max(rope_->segments(), segments_) + 1);
    default: return 1;
  }
}

// A tick's work on commands is bounded: at most kMaxCommandsPerTick of them,
// and their items at most one full set-constraints command's. The command
// that would pass that bound waits, taken from the queue, for the next tick,
// so a burst of large sets or of rope rebuilds is spread over ticks.
void Executive::apply_commands() {
  if (commands_ == nullptr) return;
  int items = 0;
  for (int n = 0; n < kMaxCommandsPerTick; ++n) {
    msg::Command& c = *held_;
    if (!holding_ && !commands_->try_pop(c)) return;
    const int cost = command_items(c);
    holding_ = n > 0 && items + cost > static_cast<int>(msg::kMaxConstraints);
    if (holding_) return;
    items += cost;
    const char* reason = "";
    const Errc e = apply(c, reason);
    if (e == Errc::ok) {
      ++counters_.commands_applied;
    } else {
      ++counters_.commands_failed;
    }
    ack(c, e, reason);
  }
}

void Executive::ack(const msg::Command& c, Errc result, const char* reason) {
  if (outputs_.acks == nullptr) return;
  msg::CommandAck a{};
  std::memcpy(a.source, c.source, sizeof a.source);
  a.sequence = c.sequence;
  a.kind = static_cast<std::uint8_t>(c.kind);
  a.result = result == Errc::ok ? msg::AckResult::applied : msg::AckResult::failed;
  msg::copy_text(a.reason, reason);
  if (!outputs_.acks->try_push(a)) ++counters_.acks_dropped;
}

// Each command's own function: checks what it is given against the pack and
// the state in force and names why it failed in `reason` (a static string:
// the tick builds no message). A refused value leaves the state as it was; a
// rope that cannot be rebuilt (model, segments) may keep new parameters.
Errc Executive::apply(const msg::Command& c, const char*& reason) {
  switch (c.kind) {
    case msg::CommandKind::set_endpoints: return apply_endpoints(c, reason);
    case msg::CommandKind::set_objective:
      objective_ = c.objective == msg::Objective::show ? Objective::show : Objective::hide;
      update_gains();
      equilibrium_.reset();
      return Errc::ok;
    case msg::CommandKind::set_weights: return apply_weights(c, reason);
    case msg::CommandKind::set_stiffness: return apply_stiffness(c, reason);
    case msg::CommandKind::set_model: return apply_model(c, reason);
    case msg::CommandKind::set_segment_count: return apply_segment_count(c, reason);
    case msg::CommandKind::set_constraints: return apply_constraints(c, reason);
    case msg::CommandKind::start:
      if (const Errc e = start_run(); e != Errc::ok) {
        reason = e == Errc::unsupported ? kUnstable : "the rope could not be laid between the endpoints";
        return Errc::invalid_argument;
      }
      counters_.running = true;
      return Errc::ok;
    case msg::CommandKind::stop:
      counters_.running = false;
      rope_->clear_point_force();
      return Errc::ok;
    case msg::CommandKind::switch_terrain: return apply_switch_terrain(c, reason);
    case msg::CommandKind::set_mode: return apply_mode(c, reason);
  }
  reason = "unknown command";
  return Errc::invalid_argument;
}

Errc Executive::apply_endpoints(const msg::Command& c, const char*& reason) {
  const storage::ResidentSampler& s = forces_->sampler();
  const Vec3 a(c.endpoints.start.x_m, c.endpoints.start.y_m, c.endpoints.start.z_m);
  const Vec3 b(c.endpoints.end.x_m, c.endpoints.end.y_m, c.endpoints.end.z_m);
  const fields::VolumeGeometry& g = s.level().geometry();
  if (!inside(a, g) || !inside(b, g)) {
    reason = "an endpoint is outside the pack or not finite";
    return Errc::invalid_argument;
  }
  if (a.z() < s.height(a.x(), a.y()) || b.z() < s.height(b.x(), b.y())) {
    reason = "an endpoint is below the terrain";
    return Errc::invalid_argument;
  }
  if ((b - a).norm() < segments_ * kMinSegmentM) {
    reason = "the endpoints are too close for the rope's segment count (0.5 m a segment at least)";
    return Errc::invalid_argument;
  }
  if (!under_ceiling(a, forces_->gains()) || !under_ceiling(b, forces_->gains())) {
    reason = "an endpoint is above the ceiling in force (max-agl, max-altitude or the field's top)";
    return Errc::invalid_argument;
  }
  const Vec3 old_start = start_m_, old_end = end_m_;
  start_m_ = a;
  end_m_ = b;
  const Errc e = start_run();
  if (e != Errc::ok) {
    start_m_ = old_start;
    end_m_ = old_end;
    reason = e == Errc::unsupported ? kUnstable : "the rope could not be laid between the endpoints";
    return Errc::invalid_argument;
  }
  return Errc::ok;
}

Errc Executive::apply_weights(const msg::Command& c, const char*& reason) {
  ForceGains g = forces_->gains();
  g.k1_visibility = c.weights.k1_visibility;  // its sign does not matter here
  g.k2_terrain = c.weights.k2_terrain;
  g.k_hull = c.weights.k4_constraint;
  const double segment_m = std::max(rope_->length_m() / rope_->segments(), 1e-3);
  if (!steps_stably(params_for(rope_->model(), rope_->segments(), segment_m), g)) {
    reason = kUnstable;
    return Errc::invalid_argument;
  }
  k1_ = c.weights.k1_visibility;
  k3_ = c.weights.k3_user;
  forces_->set_gains(g);
  update_gains();
  equilibrium_.reset();
  return Errc::ok;
}

Errc Executive::apply_stiffness(const msg::Command& c, const char*& reason) {
  const auto old_stretch = stretch_override_, old_bend = bend_override_;
  stretch_override_ = c.stiffness.stretch_n_per_m;
  bend_override_ = c.stiffness.bend_n_m_per_rad;
  const double segment_m = std::max(rope_->length_m() / rope_->segments(), 1e-3);
  const RopeParams p = params_for(rope_->model(), rope_->segments(), segment_m);
  const bool stable = steps_stably(p, forces_->gains());
  if (!stable || rope_->set_params(p) != Errc::ok) {
    stretch_override_ = old_stretch;  // not kept for later starts either
    bend_override_ = old_bend;
    reason = stable ? "the rope refused these stiffness values" : kUnstable;
    return Errc::invalid_argument;
  }
  equilibrium_.reset();
  return Errc::ok;
}

int Executive::copy_vertices() {
  const int n = rope_->segments() + 1;
  std::copy(rope_->vertices(), rope_->vertices() + n, scratch_.get());
  return n;
}

Errc Executive::apply_model(const msg::Command& c, const char*& reason) {
  const RopeModel m = c.model == msg::RopeModel::spring_mass ? RopeModel::spring : RopeModel::articulated;
  if (m == rope_->model()) return Errc::ok;
  if (spooling()) {
    reason = kSpooling;
    return Errc::invalid_argument;
  }
  const int n = copy_vertices();
  const Errc e = restart_rope(scratch_.get(), n, rope_->segments(), m);
  if (e != Errc::ok) {
    reason = e == Errc::unsupported ? kUnstable : "the rope could not be rebuilt in that model";
    return Errc::invalid_argument;
  }
  return Errc::ok;
}

Errc Executive::apply_segment_count(const msg::Command& c, const char*& reason) {
  const int segments = static_cast<int>(c.segment_count);
  if (segments < 2 || segments > config_.max_segments) {
    reason = "segment count outside what the console reserved";
    return Errc::invalid_argument;
  }
  if (spooling()) {
    reason = kSpooling;
    return Errc::invalid_argument;
  }
  const int n = copy_vertices();
  const Errc e = restart_rope(scratch_.get(), n, segments, rope_->model());
  if (e != Errc::ok) {
    reason = e == Errc::unsupported ? kUnstable : "the rope could not be resampled";
    return Errc::invalid_argument;
  }
  return Errc::ok;
}

Errc Executive::apply_switch_terrain(const msg::Command& c, const char*& reason) {
  if (c.pack_id[0] == '\0') {
    reason = "switch-terrain names no pack";
    return Errc::invalid_argument;
  }
  if (std::strncmp(c.pack_id, config_.pack_id, sizeof c.pack_id) == 0) {
    reason = "the console is on that pack already";
    return Errc::invalid_argument;
  }
  if (switch_requested_.load(std::memory_order_acquire)) {  // pairs with cancel_terrain_switch()
    reason = "a terrain switch is already under way";
    return Errc::invalid_argument;
  }
  // the console ends this session and starts one on that pack
  std::memcpy(switch_pack_id_, c.pack_id, sizeof switch_pack_id_);
  switch_pack_id_[sizeof switch_pack_id_ - 1] = '\0';
  switch_requested_.store(true, std::memory_order_release);
  return Errc::ok;
}

// The configured observers: at most kMaxObserversPerKind of a kind, each
// inside the pack and at or above the finest terrain.
Status Executive::check_observers(const HullRequest& r) const {
  if (r.hidden_count < 0 || r.visible_count < 0 || r.hidden_count > kMaxObserversPerKind ||
      r.visible_count > kMaxObserversPerKind) {
    return invalid_argument("executive: at most " + std::to_string(kMaxObserversPerKind) +
                            " hidden-from and as many visible-to points");
  }
  const fields::VolumeGeometry& g = field_.level(0).geometry();
  for (int k = 0; k < r.observers(); ++k) {
    const bool hidden = k < r.hidden_count;
    const Vec3 p = HullRequest::point(hidden ? r.hidden_from_m[k] : r.visible_to_m[k - r.hidden_count]);
    const std::string name = std::string(hidden ? "hidden-from point " : "visible-to point ") +
                             std::to_string(1 + (hidden ? k : k - r.hidden_count));
    VISVOL_RETURN_IF_ERROR(check_point(name.c_str(), p, g, finest_.height(p.x(), p.y()) - kHeightTolM));
    VISVOL_RETURN_IF_ERROR(check_observer_altitude(name, p.z()));
    int pi = 0, pj = 0;
    if (!hull_post(field_.level(config_.level).geometry(), p, pi, pj)) {
      return invalid_argument("executive: " + name + " is outside level " + std::to_string(config_.level) +
                              ", where its hull is built");
    }
  }
  return {};
}

// An endpoint under the ceiling of `g` (on the finest terrain).
// (and under the field's top, above which F_p is not known, as the planner's)
bool Executive::under_ceiling(const Vec3& p, const ForceGains& g) const {
  const double agl = p.z() - finest_.height(p.x(), p.y());
  return agl <= g.max_agl_m + kHeightTolM && p.z() <= g.max_altitude_m + kHeightTolM &&
         p.z() <= field_.level(0).geometry().top_m() + kHeightTolM;
}

Status Executive::check_ceiling(const char* name, const Vec3& p, const ForceGains& g) const {
  if (under_ceiling(p, g)) return {};
  const double agl = p.z() - finest_.height(p.x(), p.y());
  return invalid_argument(std::string(name) + ": " + std::to_string(agl) + " m above the terrain and " +
                          std::to_string(p.z()) + " m high, above the ceiling (max-agl " + std::to_string(g.max_agl_m) +
                          " m, max-altitude " + std::to_string(g.max_altitude_m) + " m, the field's top " +
                          std::to_string(field_.level(0).geometry().top_m()) + " m)");
}

// Why an observer of a command cannot be had (null: it can). Real-time safe.
const char* Executive::observer_problem(const msg::Constraint& k) const {
  const Vec3 p(k.position.x_m, k.position.y_m, k.position.z_m);
  int pi = 0, pj = 0;
  // on the finest level and on the one the hulls are built on (a coarser
  // level's posts stop up to half a post short of the finest's edge)
  if (!p.allFinite() || !hull_post(field_.level(0).geometry(), p, pi, pj) ||
      !hull_post(field_.level(config_.level).geometry(), p, pi, pj)) {
    return "a hidden-from or visible-to point is outside the pack";
  }
  if (p.z() < finest_.height(p.x(), p.y()) - kHeightTolM)
    return "a hidden-from or visible-to point is below the terrain";
  if (p.z() > kMaxObserverAltitudeM) return "a hidden-from or visible-to point is above 100 km";
  return nullptr;
}

// set-constraints: the observers are replaced (none given clears them; in
// force once the builder has their hulls); the clearance and the ceiling
// change, at once, where the command gives them. All or nothing: a command
// refused for any item changes nothing.
Errc Executive::apply_constraints(const msg::Command& c, const char*& reason) {
  ForceGains gains = forces_->gains();
  HullRequest r;
  r.eye_height_m = config_.eye_height_m;
  const Errc e = read_constraints(c, gains, r, reason);
  if (e != Errc::ok) return e;
  if (const char* problem = constraints_problem(gains, r)) {
    reason = problem;
    return Errc::invalid_argument;
  }
  forces_->set_gains(gains);
  if (hulls_ != nullptr) {
    // until the hulls are in force (or refused) the path is not at rest under them
    r.sequence = ++hull_requests_;
    hull_pending_ = r.sequence;
    hulls_->request(r);
  }
  equilibrium_.reset();
  counters_.converged = false;
  return Errc::ok;
}

// The command's items into `gains` (clearance, ceiling) and `r` (observers,
// each checked on its own).
Errc Executive::read_constraints(const msg::Command& c, ForceGains& gains, HullRequest& r, const char*& reason) const {
  const std::uint32_t n =
      std::min<std::uint32_t>(c.constraints.count, static_cast<std::uint32_t>(msg::kMaxConstraints));
  for (std::uint32_t i = 0; i < n; ++i) {
    const msg::Constraint& k = c.constraints.items[i];
    switch (k.kind) {
      case msg::ConstraintKind::clearance: gains.clearance_m = k.height_m; continue;
      case msg::ConstraintKind::max_agl: gains.max_agl_m = k.height_m; continue;
      case msg::ConstraintKind::max_altitude: gains.max_altitude_m = k.height_m; continue;
      case msg::ConstraintKind::hidden_from:
      case msg::ConstraintKind::visible_to: break;
    }
    if (hulls_ == nullptr) {
      reason =
          "hidden-from and visible-to constraints are not supported without the console's hull builder "
          "(visvol plan --hidden-from/--visible-to)";
      return Errc::unsupported;
    }
    if (const char* problem = observer_problem(k)) {
      reason = problem;
      return Errc::invalid_argument;
    }
    const Vec3 p(k.position.x_m, k.position.y_m, k.position.z_m);
    if (!(k.kind == msg::ConstraintKind::hidden_from ? r.add_hidden_from(p) : r.add_visible_to(p))) {
      static_assert(kMaxObserversPerKind == 256, "the reason names the number");
      reason = "more than 256 hidden-from or 256 visible-to points";
      return Errc::invalid_argument;
    }
  }
  return Errc::ok;
}

// Why a whole set cannot be had (null: it can): more observers than
// reserved, a clearance or ceiling that is no height, a ceiling not above
// the clearance or under the rope's ends. Real-time safe.
const char* Executive::constraints_problem(const ForceGains& g, const HullRequest& r) const {
  if (hulls_ != nullptr && r.observers() > hulls_->max_observers()) {
    return "more hidden-from and visible-to points than the console takes (--max-observers)";
  }
  if (!(std::isfinite(g.clearance_m) && g.clearance_m >= 0) || std::isnan(g.max_agl_m) ||
      std::isnan(g.max_altitude_m)) {
    return "a clearance or ceiling is not a height";
  }
  if (!(g.max_agl_m > g.clearance_m)) return "max-agl is not above the clearance: no height is allowed";
  if (!under_ceiling(start_m_, g) || !under_ceiling(end_m_, g)) {
    return "the rope's ends are above that ceiling (move them with set-endpoints first)";
  }
  if (!steps_stably(rope_->params(), g)) return kUnstable;  // a thin clearance margin is a stiff push
  return nullptr;
}

bool Executive::terrain_switch(char (&pack_id)[msg::kPackIdCapacity]) const {
  if (!switch_requested_.load(std::memory_order_acquire)) return false;
  std::memcpy(pack_id, switch_pack_id_, sizeof pack_id);
  return true;
}

}  // namespace visvol::rt
