#include "rt/exec/executive.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rt/rope/path_metrics.hpp"
#include "rt/rope/planner.hpp"
#include "rt/rope/slack.hpp"

namespace visvol::rt {

namespace {

static_assert(kMaxPlanObservers == kMaxObserversPerKind, "the console takes as many observers as the planner");
static_assert(msg::kMaxObserversPerKind == static_cast<std::size_t>(kMaxObserversPerKind),
              "a command's observers of a kind are what a hull request holds");

constexpr double kHeightTolM = 0.01;  // heights compare to a centimetre (as rt::PathChecker)

std::size_t index_of(RopeModel m) { return m == RopeModel::articulated ? 1 : 0; }

msg::DeviceState device_state_of(HapticState s, bool forces) {
  switch (s) {
    case HapticState::boot: return msg::DeviceState::disconnected;
    case HapticState::pre_operational: return msg::DeviceState::idle;
    case HapticState::operational: return forces ? msg::DeviceState::active : msg::DeviceState::idle;
    case HapticState::fault: return msg::DeviceState::fault;
  }
  return msg::DeviceState::unknown;
}

// Finite and over the grid: what every endpoint must be (real-time safe).
bool inside(const Vec3& p, const fields::VolumeGeometry& g) {
  const double x1 = g.origin_x + (g.nx - 1) * g.spacing_m, y0 = g.origin_y - (g.ny - 1) * g.spacing_m;
  return p.allFinite() && p.x() >= g.origin_x && p.x() <= x1 && p.y() >= y0 && p.y() <= g.origin_y;
}

// Whether every vertex of a rope is finite (real-time safe, O(vertices)).
bool finite_rope(const Rope& rope) {
  const Vec3* v = rope.vertices();
  double sum = 0;
  for (int i = 0; i <= rope.segments(); ++i) sum += v[i].x() + v[i].y() + v[i].z();
  return std::isfinite(sum);
}

Status check_point(const char* name, const Vec3& p, const fields::VolumeGeometry& g, double ground_m) {
  const double x1 = g.origin_x + (g.nx - 1) * g.spacing_m, y0 = g.origin_y - (g.ny - 1) * g.spacing_m;
  if (!inside(p, g)) {
    return invalid_argument(std::string(name) + ": (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                            ") is outside the pack (x " + std::to_string(g.origin_x) + ".." + std::to_string(x1) +
                            ", y " + std::to_string(y0) + ".." + std::to_string(g.origin_y) + ")");
  }
  if (p.z() < ground_m) {
    return invalid_argument(std::string(name) + ": " + std::to_string(ground_m - p.z()) + " m below the terrain");
  }
  return {};
}

// The clearance and ceiling themselves: finite where they must be, a ceiling
// above the clearance.
Status check_envelope(const ForceGains& g) {
  if (!(std::isfinite(g.clearance_m) && g.clearance_m >= 0 && g.clearance_m <= 1e4)) {
    return invalid_argument("executive: clearance " + std::to_string(g.clearance_m) + " m is outside [0, 10000]");
  }
  if (!(g.max_agl_m > g.clearance_m)) {  // NaN too
    return invalid_argument("executive: max-agl " + std::to_string(g.max_agl_m) + " m is not above the clearance " +
                            std::to_string(g.clearance_m) + " m");
  }
  if (std::isnan(g.max_altitude_m) || g.max_altitude_m == -INFINITY) {
    return invalid_argument("executive: max-altitude must be a height (or infinite: none)");
  }
  return {};
}

}  // namespace

Executive::Executive(const ExecutiveConfig& config, storage::ResidentPack& field) : config_(config), field_(field) {}

Executive::~Executive() = default;

Result<std::unique_ptr<Executive>> Executive::create(const ExecutiveConfig& config, storage::ResidentPack& field,
                                                     HapticDevice* device, DeviceSimulation* simulation,
                                                     msg::CommandQueue* commands, const ExecutiveOutputs& outputs) {
  std::unique_ptr<Executive> e(new Executive(config, field));
  VISVOL_RETURN_IF_ERROR(e->init(device, simulation, commands, outputs));
  return e;
}

Status Executive::init(HapticDevice* device, DeviceSimulation* simulation, msg::CommandQueue* commands,
                       const ExecutiveOutputs& outputs) {
  const ExecutiveConfig& c = config_;
  if (c.level < 0 || c.level >= field_.level_count()) {
    return invalid_argument("executive: level " + std::to_string(c.level) + " is not in the pack (0.." +
                            std::to_string(field_.level_count() - 1) + ")");
  }
  if (c.max_segments < 2 || c.max_segments > 100000 ||
      c.max_segments + 1 > static_cast<int>(msg::kMaxPathVertices) * 64) {
    return invalid_argument("executive: max segments " + std::to_string(c.max_segments) + " is outside 2..100000");
  }
  if (c.segments < 2 || c.segments > c.max_segments) {
    return invalid_argument("executive: segments " + std::to_string(c.segments) + " is outside 2.." +
                            std::to_string(c.max_segments) + " (the reserved maximum)");
  }
  if (!(c.period_s > 0 && c.period_s <= 0.1)) return invalid_argument("executive: period must be in (0, 0.1] s");
  for (int every : {c.path_every_ticks, c.fc_every_ticks, c.focus_every_ticks, c.device_every_ticks}) {
    if (every < 1) return invalid_argument("executive: hand-off intervals must be at least one tick");
  }
  if (c.fc_samples < 2) return invalid_argument("executive: fc_samples must be at least 2");
  if (!(std::isfinite(c.stiffness) && c.stiffness > 0))
    return invalid_argument("executive: stiffness must be positive");
  if (!(std::isfinite(c.slack) && c.slack >= 0 && c.slack <= 10))
    return invalid_argument("executive: slack must be in [0, 10]");
  if (!(std::isfinite(c.k3_user) && c.k3_user >= 0)) return invalid_argument("executive: k3 must be >= 0");
  if (!(c.workspace_half_mm > 1 && c.workspace_half_mm < 1000)) {
    return invalid_argument("executive: workspace half-size must be in (1, 1000) mm");
  }
  VISVOL_RETURN_IF_ERROR(check_envelope(c.gains));
  if (!(std::isfinite(c.eye_height_m) && c.eye_height_m >= 0 && c.eye_height_m <= 1e4)) {
    return invalid_argument("executive: eye height must be in [0, 10000] m");
  }

  // the region around the endpoints resident before anything samples it
  const storage::ResidentLevel& level = field_.level(c.level);
  const fields::VolumeGeometry& g = level.geometry();
  storage::WorldBox box{std::min(c.start_m.x(), c.end_m.x()), std::min(c.start_m.y(), c.end_m.y()),
                        std::max(c.start_m.x(), c.end_m.x()), std::max(c.start_m.y(), c.end_m.y())};
  field_.set_focus(box);
  VISVOL_RETURN_IF_ERROR(field_.update());
  forces_ = std::make_unique<FieldForces<storage::ResidentLevel, storage::ResidentSampler>>(level, c.gains);
  if (c.planning_bounds) forces_->set_bounds(*c.planning_bounds);
  const storage::ResidentSampler& sampler = forces_->sampler();
  VISVOL_RETURN_IF_ERROR(check_point("start", c.start_m, g, sampler.height(c.start_m.x(), c.start_m.y())));
  VISVOL_RETURN_IF_ERROR(check_point("end", c.end_m, g, sampler.height(c.end_m.x(), c.end_m.y())));
  const Vec3 ends[2] = {c.start_m, c.end_m};
  VISVOL_RETURN_IF_ERROR(
      describe_polyline(ends, 2, c.segments, 2, c.max_segments).with_context("executive: start to end"));
  finest_ = fields::FieldSampler<storage::ResidentLevel>(field_.level(0));
  VISVOL_RETURN_IF_ERROR(check_ceiling("start", c.start_m, c.gains));
  VISVOL_RETURN_IF_ERROR(check_ceiling("end", c.end_m, c.gains));
  config_.observers.eye_height_m = c.eye_height_m;
  VISVOL_RETURN_IF_ERROR(check_observers(config_.observers));

  start_m_ = c.start_m;
  end_m_ = c.end_m;
  objective_ = c.objective;
  segments_ = c.segments;
  stiffness_ = c.stiffness;
  k1_ = std::fabs(c.gains.k1_visibility);
  k3_ = c.k3_user;
  update_gains();
  EquilibriumCriteria criteria;
  criteria.check_interval_s = c.fc_every_ticks * c.period_s;
  criteria.max_rms_speed_mps = 0.1 * g.spacing_m;
  equilibrium_.configure(criteria);

  for (RopeModel m : {RopeModel::spring, RopeModel::articulated}) {
    RopeParams p = params_for(m, c.segments, std::max((c.end_m - c.start_m).norm() / c.segments, 1.0));
    p.max_segments = c.max_segments;
    Result<std::unique_ptr<Rope>> rope = make_rope(p);
    if (!rope.ok()) return rope.status().with_context("executive");
    ropes_[index_of(m)] = std::move(*rope);
  }
  rope_ = ropes_[index_of(c.model)].get();
  scratch_ = std::make_unique<Vec3[]>(static_cast<std::size_t>(c.max_segments) + 1);
  path_sample_ = std::make_unique<msg::PathSample>();
  held_ = std::make_unique<msg::Command>();
  if (start_run() != Errc::ok) return invalid_argument("executive: the rope could not be laid between the endpoints");
  counters_.running = c.start_running;
  counters_.fc = path_fc(rope_->vertices(), rope_->segments() + 1, *forces_, c.fc_samples);
  counters_.length_m = rope_->length_m();

  simulation_ = simulation;
  commands_ = commands;
  outputs_ = outputs;
  if (device != nullptr) {
    // the rope's extent onto the device's workspace; the soft joint as the hand feels it
    const double span_m = std::max((c.end_m - c.start_m).head<2>().norm(), 10.0 * g.spacing_m);
    servo::ServoConfig sc = c.servo;
    sc.world_m_per_device_mm = span_m / (2.0 * c.workspace_half_mm);
    sc.world_offset_m = 0.5 * (c.start_m + c.end_m);
    const double hand_m_per_world_m = 1.0 / (1000.0 * sc.world_m_per_device_mm);
    sc.coupling_stiffness_n_per_m = c.hand_stiffness_n_per_m * hand_m_per_world_m / sc.hand_per_rope_force;
    sc.coupling_damping_n_s_per_m = c.hand_damping_n_s_per_m * hand_m_per_world_m / sc.hand_per_rope_force;
    const double ref = forces_->reference_gradient();
    sc.cue_gain_n_m = ref > 0 ? -c.cue_n / ref : 0.0;
    Result<servo::Servo> servo = servo::Servo::create(sc);
    if (!servo.ok()) return servo.status().with_context("executive: servo");
    servo_.emplace(std::move(*servo));
    device_ = device;
    last_proxy_m_ = sc.world_offset_m;
    // 1 mm of hand travel pulls as hard as the saturated field (k3 = 1); the
    // pull is capped at ten times that, which the rope's step still takes
    const double saturated_n = FieldForces<storage::ResidentLevel, storage::ResidentSampler>::kSaturation *
                               rope_->params().mass_kg * forces_->reference_acceleration();
    const double pull_at_1mm_n = sc.coupling_stiffness_n_per_m * sc.world_m_per_device_mm;
    user_force_per_n_ = saturated_n / pull_at_1mm_n;
    max_user_force_n_ = 10.0 * saturated_n;
    counters_.haptics = true;
  }
  return {};
}

RopeParams Executive::params_for(RopeModel model, int segments, double segment_m) const {
  RopeParams p = scaled_rope_params(model, segments, segment_m, stiffness_, forces_->reference_acceleration());
  p.max_segments = config_.max_segments;
  if (stretch_override_) {
    p.stretch_stiffness_n_per_m = *stretch_override_;
    p.stretch_damping_n_s_per_m = 0.6 * std::sqrt(p.stretch_stiffness_n_per_m * p.mass_kg);
  }
  if (bend_override_) {
    p.bend_stiffness_n_m_per_rad = *bend_override_;
    p.twist_stiffness_n_m_per_rad = 0.1 * p.bend_stiffness_n_m_per_rad;
    p.bend_spring_n_per_m = *bend_override_ / (segment_m * segment_m);  // the spring model's i..i+2 springs
  }
  return p;
}

void Executive::update_gains() {
  ForceGains g = forces_ ? forces_->gains() : config_.gains;
  g.k1_visibility = (objective_ == Objective::hide ? -1.0 : 1.0) * k1_;
  if (forces_) forces_->set_gains(g);
}

Errc Executive::start_run() {
  relaid_ = false;
  const int n = segments_;
  const double straight = (end_m_ - start_m_).norm();
  const double length = rope_->model() == RopeModel::articulated ? straight * (1.0 + config_.slack) : straight;
  const storage::ResidentSampler& s = forces_->sampler();
  const Vec3 a = start_m_, b = end_m_;
  // 20 m above the clearance, or half way up to a lower ceiling
  const ForceGains& gains = forces_->gains();
  const double lay_agl_m = std::min(gains.clearance_m + 20.0, 0.5 * (gains.clearance_m + gains.max_agl_m));
  lay_with_slack([&](int i) { return Vec3(a + (static_cast<double>(i) / n) * (b - a)); }, n, 1, length, lay_agl_m,
                 s.level().geometry(), [&](double x, double y) { return s.height(x, y); }, scratch_.get());
  // checked first: a refusal from reset() would build a message on this thread
  if (check_polyline(scratch_.get(), n + 1, n, 2, config_.max_segments) != Errc::ok) return Errc::invalid_argument;
  const Errc e = rope_->set_params(params_for(rope_->model(), n, std::max(length / n, 1e-3)));
  if (e != Errc::ok) return e;
  if (!rope_->reset(scratch_.get(), n + 1, n).ok()) return Errc::invalid_argument;
  set_ends(start_m_, end_m_);
  equilibrium_.reset();
  grasping_ = false;
  rope_->clear_point_force();
  counters_.converged = false;
  counters_.run_s = 0;
  counters_.equilibrium_s = 0;
  ++counters_.runs;
  return Errc::ok;
}

Errc Executive::restart_rope(const Vec3* polyline, int points, int segments, RopeModel model) {
  Rope* next = ropes_[index_of(model)].get();
  if (check_polyline(polyline, points, segments, 2, config_.max_segments) != Errc::ok) return Errc::invalid_argument;
  const double length = polyline_length_m(polyline, points);
  const Errc e = next->set_params(params_for(model, segments, std::max(length / segments, 1e-3)));
  if (e != Errc::ok) return e;
  if (!next->reset(polyline, points, segments).ok()) return Errc::invalid_argument;
  rope_ = next;
  segments_ = segments;
  set_ends(start_m_, end_m_);
  equilibrium_.reset();
  grasping_ = false;
  rope_->clear_point_force();
  counters_.converged = false;
  return Errc::ok;
}

void Executive::set_ends(const Vec3& start, const Vec3& end) {
  RopeEnds ends;
  ends.start_m = start;
  ends.end_m = end;
  rope_->set_ends(ends);
}

// ---- commands -------------------------------------------------------------

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
    case msg::CommandKind::set_model: return bounded(rope_->segments() + 1);
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
    case msg::CommandKind::set_weights: return apply_weights(c);
    case msg::CommandKind::set_stiffness: return apply_stiffness(c, reason);
    case msg::CommandKind::set_model: return apply_model(c, reason);
    case msg::CommandKind::set_segment_count: return apply_segment_count(c, reason);
    case msg::CommandKind::set_constraints: return apply_constraints(c, reason);
    case msg::CommandKind::start:
      if (start_run() != Errc::ok) {
        reason = "the rope could not be laid between the endpoints";
        return Errc::invalid_argument;
      }
      counters_.running = true;
      return Errc::ok;
    case msg::CommandKind::stop:
      counters_.running = false;
      rope_->clear_point_force();
      return Errc::ok;
    case msg::CommandKind::switch_terrain: return apply_switch_terrain(c, reason);
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
    reason = "an endpoint is above the ceiling in force (max-agl or max-altitude)";
    return Errc::invalid_argument;
  }
  const Vec3 old_start = start_m_, old_end = end_m_;
  start_m_ = a;
  end_m_ = b;
  if (start_run() != Errc::ok) {
    start_m_ = old_start;
    end_m_ = old_end;
    reason = "the rope could not be laid between the endpoints";
    return Errc::invalid_argument;
  }
  return Errc::ok;
}

Errc Executive::apply_weights(const msg::Command& c) {
  k1_ = c.weights.k1_visibility;
  k3_ = c.weights.k3_user;
  ForceGains g = forces_->gains();
  g.k2_terrain = c.weights.k2_terrain;
  g.k_hull = c.weights.k4_constraint;
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
  if (rope_->set_params(params_for(rope_->model(), rope_->segments(), segment_m)) != Errc::ok) {
    stretch_override_ = old_stretch;  // not kept for later starts either
    bend_override_ = old_bend;
    reason = "the rope refused these stiffness values";
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
  const int n = copy_vertices();
  if (restart_rope(scratch_.get(), n, rope_->segments(), m) != Errc::ok) {
    reason = "the rope could not be rebuilt in that model";
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
  const int n = copy_vertices();
  if (restart_rope(scratch_.get(), n, segments, rope_->model()) != Errc::ok) {
    reason = "the rope could not be resampled";
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
  if (switch_requested_.load(std::memory_order_relaxed)) {
    reason = "a terrain switch is already under way";
    return Errc::invalid_argument;
  }
  // the console ends this session and starts one on that pack
  std::memcpy(switch_pack_id_, c.pack_id, sizeof switch_pack_id_);
  switch_pack_id_[sizeof switch_pack_id_ - 1] = '\0';
  switch_requested_.store(true, std::memory_order_release);
  return Errc::ok;
}

Status Executive::set_constraint_hulls(ConstraintHulls* hulls) {
  if (hulls != nullptr && &hulls->level() != &field_.level(config_.level)) {
    return Status(Errc::invalid_argument, "constraint hulls: built on another level than the executive's");
  }
  const HullRequest& r = config_.observers;
  if (r.observers() > 0 && hulls == nullptr) {
    return invalid_argument("executive: hidden-from and visible-to points need the hull builder");
  }
  if (hulls != nullptr && r.observers() > hulls->max_observers()) {
    return invalid_argument("executive: " + std::to_string(r.observers()) +
                            " hidden-from and visible-to points, the console takes " +
                            std::to_string(hulls->max_observers()) + " (--max-observers)");
  }
  hulls_ = hulls;
  if (hulls_ != nullptr && r.observers() > 0) {
    HullRequest first = r;
    first.sequence = ++hull_requests_;
    hull_pending_ = first.sequence;
    hulls_->request(first);
  }
  return Status::ok_status();
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
    int pi = 0, pj = 0;
    if (!hull_post(field_.level(config_.level).geometry(), p, pi, pj)) {
      return invalid_argument("executive: " + name + " is outside level " + std::to_string(config_.level) +
                              ", where its hull is built");
    }
  }
  return {};
}

// An endpoint under the ceiling of `g` (on the finest terrain).
bool Executive::under_ceiling(const Vec3& p, const ForceGains& g) const {
  const double agl = p.z() - finest_.height(p.x(), p.y());
  return agl <= g.max_agl_m + kHeightTolM && p.z() <= g.max_altitude_m + kHeightTolM;
}

Status Executive::check_ceiling(const char* name, const Vec3& p, const ForceGains& g) const {
  if (under_ceiling(p, g)) return {};
  const double agl = p.z() - finest_.height(p.x(), p.y());
  return invalid_argument(std::string(name) + ": " + std::to_string(agl) + " m above the terrain and " +
                          std::to_string(p.z()) + " m high, above the ceiling (max-agl " + std::to_string(g.max_agl_m) +
                          " m, max-altitude " + std::to_string(g.max_altitude_m) + " m)");
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
  return nullptr;
}

bool Executive::terrain_switch(char (&pack_id)[msg::kPackIdCapacity]) const {
  if (!switch_requested_.load(std::memory_order_acquire)) return false;
  std::memcpy(pack_id, switch_pack_id_, sizeof pack_id);
  return true;
}

void Executive::install_hulls() {
  if (hull_pending_ != 0 && hulls_->refused_sequence() == hull_pending_) hull_pending_ = 0;
  const HullSet* set = hulls_->take();
  if (set == nullptr) return;
  if (set->sequence() == hull_pending_) hull_pending_ = 0;
  forces_->set_hidden_from(set->hidden);  // each kind folded into one hull
  forces_->set_visible_to(set->visible);
  in_force_ = set;
  ++counters_.hull_sets;
  equilibrium_.reset();
}

// ---- the tick ---------------------------------------------------------------

void Executive::warm_up() {
  // one pass over everything a tick touches: code, the rope's buffers, samples
  const double fc = path_fc(rope_->vertices(), rope_->segments() + 1, *forces_, config_.fc_samples);
  counters_.fc = fc;
  counters_.length_m = rope_->length_m();
  hand_off_focus();
}

void Executive::safe_state() {
  ++counters_.safe_states;
  if (servo_) servo_->force_safe_state();
}

int Executive::nearest_point(const Vec3& p, double& fraction) const {
  const Vec3* v = rope_->vertices();
  int best = 0;
  double best_d2 = INFINITY;
  fraction = 0;
  for (int i = 0; i < rope_->segments(); ++i) {
    const Vec3 d = v[i + 1] - v[i];
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - v[i]).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double d2 = (v[i] + t * d - p).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = i;
      fraction = t;
    }
  }
  return best;
}

void Executive::haptics(std::int64_t now_ns, double t_s) {
  device_now_ns_ = now_ns;
  device_->poll(now_ns);
  const HapticSample& sample = device_->sample();
  servo::ServoInput in;
  in.time_s = t_s;
  in.device_pos_mm = sample.position_mm;
  in.grasp_button = sample.grasp_button;
  in.clutch_button = sample.clutch_button;
  in.sample_fresh = sample.fresh;
  in.sample_valid = sample.valid;
  in.device_operational = device_->state() == HapticState::operational;
  in.point_valid = true;
  if (!grasping_) {
    // the point a grasp would take: nearest the proxy of the last tick
    grasp_segment_ = nearest_point(last_proxy_m_, grasp_fraction_);
  }
  in.point_pos_m = rope_->point(grasp_segment_, grasp_fraction_);
  in.point_vel_m_per_s = rope_->point_velocity(grasp_segment_, grasp_fraction_);
  const Vec3 grad = forces_->sampler().gradient(in.point_pos_m.x(), in.point_pos_m.y(), in.point_pos_m.z());
  in.grad_fp_per_m = objective_ == Objective::hide ? grad : Vec3(-grad);
  out_ = servo_->step(in);
  last_proxy_m_ = out_.proxy_pos_m;
  if (out_.grasping && !grasping_) ++counters_.grasps;
  grasping_ = out_.grasping && counters_.running;
  if (grasping_) {
    Vec3 pull = (k3_ * user_force_per_n_) * out_.rope_force_n;
    const double n = pull.norm();
    if (n > max_user_force_n_) pull *= max_user_force_n_ / n;
    rope_->set_point_force(grasp_segment_, grasp_fraction_, pull);
  } else {
    rope_->clear_point_force();
  }
  counters_.servo_reason = out_.safe_reason;
  counters_.device_state = device_->state();
}

void Executive::tick(const TickTime& time) {
  const std::int64_t now_ns = time.woke_ns;
  apply_commands();  // 1
  if (hulls_ != nullptr) install_hulls();
  if (simulation_ != nullptr) simulation_->step(now_ns);                        // 2
  if (device_ != nullptr) haptics(now_ns, static_cast<double>(now_ns) * 1e-9);  // 3, 4
  if (counters_.running) {                                                      // 5
    rope_->step(config_.period_s, *forces_);
    counters_.run_s += config_.period_s;
    if (!finite_rope(*rope_)) recover_rope();
  }
  if (device_ != nullptr) {  // 6
    const Errc sent = device_->command(out_.device_force_n, out_.device_enable);
    if (sent != Errc::ok && sent != Errc::state) ++counters_.send_failures;
  }
  const std::uint64_t n = ++counters_.ticks;  // 7
  if (counters_.running && n % static_cast<std::uint64_t>(config_.fc_every_ticks) == 0) measure();
  const bool path_due = n % static_cast<std::uint64_t>(config_.path_every_ticks) == 0;
  const bool device_due = n % static_cast<std::uint64_t>(config_.device_every_ticks) == 0;
  if (path_due || device_due) {
    const std::int64_t stamp = msg::now_stamp_ns();
    if (path_due) hand_off_path(stamp);
    if (device_due) {
      hand_off_device(stamp);
      snapshot_.write(counters_);
    }
  }
  if (n % static_cast<std::uint64_t>(config_.focus_every_ticks) == 0) hand_off_focus();
  field_.tick_done();
}

// A rope whose state stopped being finite is laid again between its ends and
// let go of (MuJoCo resets on bad numbers likewise); it stops when even that
// fails. Counted, never logged: this runs on the loop thread.
// The hand is let go of (forces return only with a new grasp), and an
// operator's stiffness, the likely cause, is dropped; a rope that diverges
// again within a simulated second of being laid stops.
void Executive::recover_rope() {
  ++counters_.rope_resets;
  if (servo_) servo_->force_safe_state();
  const bool again = relaid_ && counters_.run_s < 1.0;
  stretch_override_.reset();
  bend_override_.reset();
  if (again || start_run() != Errc::ok) {
    counters_.running = false;
    rope_->clear_point_force();
    return;
  }
  relaid_ = true;
  --counters_.runs;  // the same run, laid again
}

void Executive::measure() {
  const int n = rope_->segments() + 1;
  const double fc = path_fc(rope_->vertices(), n, *forces_, config_.fc_samples);
  const double rms = std::sqrt(2.0 * rope_->kinetic_energy_j() / (rope_->params().mass_kg * n));
  counters_.fc = fc;
  counters_.length_m = rope_->length_m();
  const bool at_rest = equilibrium_.add(rms, fc) && hull_pending_ == 0;
  if (at_rest && !counters_.converged && counters_.equilibrium_s == 0) counters_.equilibrium_s = counters_.run_s;
  counters_.converged = at_rest;
}

void Executive::hand_off_path(std::int64_t stamp_ns) {
  if (outputs_.path == nullptr && outputs_.path_render == nullptr && outputs_.limited_path == nullptr) return;
  if (!finite_rope(*rope_)) return;  // a rope that could not be recovered is not published
  msg::PathSample& p = *path_sample_;
  const storage::ResidentSampler& s = forces_->sampler();
  p.sequence = ++path_sequence_;
  p.stamp_ns = stamp_ns;
  std::memcpy(p.pack_id, config_.pack_id, sizeof p.pack_id);
  p.objective = objective_ == Objective::show ? msg::Objective::show : msg::Objective::hide;
  p.converged = counters_.converged;
  p.inside_envelope = false;  // the rope's own path: the flyable-path thread fits it
  p.f_c = counters_.fc;
  p.length_m = rope_->length_m();
  const int count = rope_->segments() + 1;
  const int keep = std::min(count, static_cast<int>(msg::kMaxPathVertices));
  const Vec3* v = rope_->vertices();
  double lowest = INFINITY;
  for (int k = 0; k < keep; ++k) {
    // evenly spaced, both ends kept
    const int i = keep == count ? k : static_cast<int>(std::lround(static_cast<double>(k) * (count - 1) / (keep - 1)));
    const Vec3& x = v[i];
    msg::PathVertex& out = p.vertices[k];
    out.position = {x.x(), x.y(), x.z()};
    out.visibility = s.visibility(x.x(), x.y(), x.z());
    out.clearance_m = x.z() - s.height(x.x(), x.y());
    lowest = std::min(lowest, out.clearance_m);
  }
  p.vertex_count = static_cast<std::uint32_t>(keep);
  p.min_clearance_m = lowest;
  if (outputs_.limited_path != nullptr) {
    LimitedPath& l = outputs_.limited_path->back();
    std::memcpy(&l.path, &p, sizeof p);
    l.limits.gains = forces_->gains();
    l.limits.observers = in_force_ != nullptr ? in_force_->request : HullRequest{};
    outputs_.limited_path->publish();
  }
  for (LatestValue<msg::PathSample>* sink : {outputs_.path, outputs_.path_render}) {
    if (sink == nullptr) continue;
    std::memcpy(&sink->back(), &p, sizeof p);
    sink->publish();
  }
  ++counters_.paths;
}

void Executive::hand_off_device(std::int64_t stamp_ns) {
  if (outputs_.device == nullptr || device_ == nullptr) return;
  msg::DeviceStatusSample& d = outputs_.device->back();
  d.sequence = ++device_sequence_;
  d.stamp_ns = stamp_ns;
  msg::copy_text(d.device, "haptic");
  const HapticHealth health = device_->health();
  d.state = device_state_of(health.state, out_.forces_enabled);
  d.fault_bits = health.fault_bits;
  d.motor_temperature_c = health.motor_temperature_c;
  const HapticSample& sample = device_->sample();
  d.last_position_age_ms =
      sample.timestamp_ns > 0 ? static_cast<double>(device_now_ns_ - sample.timestamp_ns) * 1e-6 : INFINITY;
  d.can_rx_frames = health.rx_frames;
  d.can_tx_frames = health.tx_frames;
  d.can_errors = health.errors;
  d.bus_off_count = static_cast<std::uint32_t>(health.bus_off_count);
  outputs_.device->publish();
}

void Executive::hand_off_focus() {
  const Vec3* v = rope_->vertices();
  storage::WorldBox b{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (int i = 0; i <= rope_->segments(); ++i) {
    b.x0_m = std::min(b.x0_m, v[i].x());
    b.y0_m = std::min(b.y0_m, v[i].y());
    b.x1_m = std::max(b.x1_m, v[i].x());
    b.y1_m = std::max(b.y1_m, v[i].y());
  }
  const double lead = config_.focus_lead_m;
  field_.set_focus({b.x0_m - lead, b.y0_m - lead, b.x1_m + lead, b.y1_m + lead});
}

}  // namespace visvol::rt
