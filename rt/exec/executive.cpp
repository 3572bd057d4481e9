// The executive's tick core: creation, the rope's runs, the hull hand-over and the tick. The command
// applier is in executive_commands.cpp, the reports to other threads in executive_reports.cpp.
#include "rt/exec/executive.hpp"

#include <algorithm>
#include <cmath>

#include "rt/exec/executive_detail.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/planner.hpp"
#include "rt/rope/slack.hpp"

namespace visvol::rt {

using detail::check_point;
using detail::finite_rope;

namespace {

std::size_t index_of(RopeModel m) { return m == RopeModel::articulated ? 1 : 0; }

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
  criteria.max_rms_speed_m_per_s = 0.1 * g.spacing_m;
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
  const Errc laid = start_run();
  if (laid == Errc::unsupported) {
    return invalid_argument(
        "executive: the rope would step outside its stability margin at the " + std::to_string(c.period_s * 1e3) +
        " ms period with these gains, stiffness and clearance (lower the gains or the stiffness, or "
        "widen the clearance)");
  }
  if (laid != Errc::ok) return invalid_argument("executive: the rope could not be laid between the endpoints");
  counters_.running = c.start_running;
  counters_.fc = path_fc(rope_->vertices(), rope_->segments() + 1, *forces_, c.fc_samples);
  counters_.length_m = rope_->length_m();

  simulation_ = simulation;
  commands_ = commands;
  outputs_ = outputs;
  if (device != nullptr) {
    servo::ServoConfig sc = scene_servo_config(c, g.spacing_m);
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
    saturated_n_ = saturated_n;
    counters_.haptics = true;
  }
  return {};
}

servo::ServoConfig scene_servo_config(const ExecutiveConfig& c, double spacing_m) {
  const double span_m = std::max((c.end_m - c.start_m).head<2>().norm(), 10.0 * spacing_m);
  servo::ServoConfig sc = c.servo;
  sc.world_m_per_device_mm = span_m / (2.0 * c.workspace_half_mm);
  sc.world_offset_m = 0.5 * (c.start_m + c.end_m);
  const double hand_m_per_world_m = 1.0 / (1000.0 * sc.world_m_per_device_mm);
  sc.coupling_stiffness_n_per_m = c.hand_stiffness_n_per_m * hand_m_per_world_m / sc.hand_per_rope_force;
  sc.coupling_damping_n_s_per_m = c.hand_damping_n_s_per_m * hand_m_per_world_m / sc.hand_per_rope_force;
  return sc;
}

double pull_segment_m(const Vec3& start_m, const Vec3& end_m, RopeModel model, int segments, double slack) {
  const double straight = (end_m - start_m).norm();
  const double length = model == RopeModel::articulated ? straight * (1.0 + slack) : straight;
  return std::max(length / std::max(segments, 1), kMinSegmentM);
}

Vec3 spool_lead_end_m(const Vec3& start_m, const Vec3& end_m, RopeModel model, int segments, double slack) {
  return start_m +
         kSpoolLeadSegments * pull_segment_m(start_m, end_m, model, segments, slack) * (end_m - start_m).normalized();
}

Eigen::Vector3d spool_drag_mm(const ExecutiveConfig& c, double spacing_m, double past) {
  const servo::ServoConfig sc = scene_servo_config(c, spacing_m);
  const Vec3 lead_end = spool_lead_end_m(c.start_m, c.end_m, c.model, c.segments, c.slack);
  const Vec3 target = c.end_m + past * (c.end_m - c.start_m);
  return sc.device_to_world.transpose() * (target - lead_end) / sc.world_m_per_device_mm;
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

bool Executive::steps_stably(const RopeParams& p, const ForceGains& g) const {
  if (!config_.refuse_unstable) return true;
  // Each stiff term as the square of its angular frequency (1/s^2), and the
  // planner's rule on the largest (a step of at most 0.4 / omega).
  double omega2 = 0;
  if (p.model == RopeModel::spring) {
    // a chain's highest mode: the stretch and the i..i+2 bending springs together
    omega2 = 4.0 * (p.stretch_stiffness_n_per_m + p.bend_spring_n_per_m) / p.mass_kg;
  } else {
    const double r = p.capsule_radius_m, l = 4.0 * r;  // scaled_rope_params: r = l / 4
    omega2 = 4.0 * p.bend_stiffness_n_m_per_rad / (p.mass_kg * (3 * r * r + l * l) / 12.0);
  }
  const double a = forces_->reference_acceleration();
  const double sat = FieldForces<storage::ResidentLevel>::kSaturation;
  const bool ceiling = std::isfinite(g.max_agl_m) || std::isfinite(g.max_altitude_m);
  if (g.clearance_m > 0 || ceiling) {  // the clearance and ceiling ramps: 2 sat k_c a over their margin
    omega2 = std::max(omega2, 2.0 * sat * g.k_clearance * a / std::max(0.2 * g.clearance_m, 1.0));
  }
  omega2 =
      std::max(omega2, 2.0 * g.k2_terrain * a / std::max(forces_->sampler().level().tff_params().band_offset_m, 1.0));
  omega2 = std::max(omega2, sat * g.k_hull * a / std::max(g.hull_margin_m, 1e-3));
  // the saturated visibility pull turns round within about a post: a spring
  // of 2 sat |k1| a over the post spacing
  const double spacing_m = forces_->sampler().level().geometry().spacing_m;
  omega2 = std::max(omega2, 2.0 * sat * std::fabs(g.k1_visibility) * a / std::max(spacing_m, 1e-3));
  return !(omega2 > 0 && 0.4 / std::sqrt(omega2) < config_.period_s);
}

void Executive::update_gains() {
  ForceGains g = forces_ ? forces_->gains() : config_.gains;
  g.k1_visibility = (objective_ == Objective::hide ? -1.0 : 1.0) * k1_;
  if (forces_) forces_->set_gains(g);
}

Errc Executive::start_run() {
  const int n = segments_;
  const double length = pull_segment_m(start_m_, end_m_, rope_->model(), n, config_.slack) * n;
  const storage::ResidentSampler& s = forces_->sampler();
  const Vec3 a = start_m_, b = end_m_;
  // 20 m above the clearance, or half way up to a lower ceiling
  const ForceGains& gains = forces_->gains();
  const double lay_agl_m = std::min(gains.clearance_m + 20.0, 0.5 * (gains.clearance_m + gains.max_agl_m));
  lay_with_slack([&](int i) { return Vec3(a + (static_cast<double>(i) / n) * (b - a)); }, n, 1, length, lay_agl_m,
                 s.level().geometry(), [&](double x, double y) { return s.height(x, y); }, scratch_.get());
  // checked first: a refusal from reset() would build a message on this thread
  if (check_polyline(scratch_.get(), n + 1, n, 2, config_.max_segments) != Errc::ok) return Errc::invalid_argument;
  const RopeParams p = params_for(rope_->model(), n, std::max(length / n, 1e-3));
  if (!steps_stably(p, forces_->gains())) return Errc::unsupported;
  const Errc e = rope_->set_params(p);
  if (e != Errc::ok) return e;
  if (!rope_->reset(scratch_.get(), n + 1, n).ok()) return Errc::invalid_argument;
  set_ends(start_m_, end_m_);
  equilibrium_.reset();
  counters_.converged = false;
  counters_.run_s = 0;
  counters_.equilibrium_s = 0;
  ++counters_.runs;
  relaid_ = false;  // a new run (recover_rope sets it again for a relaid one)
  const bool was_spool = mode_ != msg::InteractionMode::pull;
  if (was_spool) ++counters_.mode_switches;
  mode_ = msg::InteractionMode::pull;  // between both ends
  counters_.mode = mode_;
  arriving_ = false;
  arrival_ticks_ = -1;
  let_go(was_spool);  // a new rope under the hand; from spool mode, the scene's mapping again
  return Errc::ok;
}

Errc Executive::restart_rope(const Vec3* polyline, int points, int segments, RopeModel model) {
  Rope* next = ropes_[index_of(model)].get();
  if (check_polyline(polyline, points, segments, 2, config_.max_segments) != Errc::ok) return Errc::invalid_argument;
  const double length = polyline_length_m(polyline, points);
  const RopeParams p = params_for(model, segments, std::max(length / segments, 1e-3));
  if (!steps_stably(p, forces_->gains())) return Errc::unsupported;
  const Errc e = next->set_params(p);
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

void Executive::stopping() {
  if (servo_) servo_->force_safe_state();
  rope_->clear_point_force();
  grasping_ = false;
  if (device_ == nullptr) return;
  const Errc sent = device_->command(Eigen::Vector3d::Zero(), false);
  if (sent != Errc::ok && sent != Errc::state) ++counters_.send_failures;  // the tick's rule
  // an in-process simulated device takes its frames when stepped: once more
  if (simulation_ != nullptr && last_tick_ns_ > 0) {  // (no tick: nothing was ever commanded)
    simulation_->step(last_tick_ns_ + static_cast<std::int64_t>(config_.period_s * 1e9));
  }
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
  if (!grasping_ && spooling()) {
    // the rope's free end
    grasp_segment_ = rope_->segments() - 1;
    grasp_fraction_ = 1.0;
  } else if (!grasping_) {
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
    pull_n_ = pull;
  } else {
    rope_->clear_point_force();
    pull_n_ = Vec3::Zero();
  }
  counters_.servo_reason = out_.safe_reason;
  counters_.device_state = device_->state();
  // each press of the mode button switches pull <-> spool; its state is kept
  // through samples that are not valid (a gap is not a release)
  if (sample.valid) {
    const bool pressed = sample.mode_button;
    if (pressed && !mode_button_was_ && now_ns - mode_press_ns_ >= kModePressGuardNs) {
      const msg::InteractionMode other =
          mode_ == msg::InteractionMode::pull ? msg::InteractionMode::spool : msg::InteractionMode::pull;
      if (set_mode(other) == Errc::ok) {
        mode_press_ns_ = now_ns;
      } else {
        ++counters_.mode_refusals;
      }
    }
    mode_button_was_ = pressed;
  }
}

void Executive::tick(const TickTime& time) {
  const std::int64_t now_ns = time.woke_ns;
  last_tick_ns_ = now_ns;
  apply_commands();  // 1
  if (hulls_ != nullptr) install_hulls();
  if (simulation_ != nullptr) simulation_->step(now_ns);                        // 2
  if (device_ != nullptr) haptics(now_ns, static_cast<double>(now_ns) * 1e-9);  // 3, 4
  if (counters_.running) {                                                      // 5
    spool();
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

}  // namespace visvol::rt
