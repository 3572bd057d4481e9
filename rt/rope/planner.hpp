// The offline planner: a path a crew can fly and trust, from A to B.
//
// 1. A start: the straight segment, a polyline (a 2D one lifted to the
//    clearance above the terrain, or a 3D one), or the global graph search
//    (rt/rope/global_search.hpp), which treats hidden-from and visible-to as
//    forbidden volume and the envelope as limits: on the coarsest level, then
//    on the finest level of at most `max_search_voxels` (its optimum is the
//    bar the answer must clear).
// 2. A rope laid on the start settles in the field, coarse level of detail
//    first (from the level the global search's start was found on, else the
//    coarsest), then the finer ones, until it reaches equilibrium on the finest.
//    An inextensible (articulated) rope gets `slack` extra length, bent
//    sideways (rt/rope/slack.hpp), and settles by FIRE (a minimiser:
//    RopeParams::fire_mixing). Equilibrium: over the last half second the
//    rope's RMS speed stays under a tenth of a post spacing per second and F_c
//    changes by less than 0.2% of itself per second (plus 1e-6).
// 3. Every path seen (the start, each search, the rope every
//    `candidate_interval_s` on the finest level and at the end of every level
//    it settled on)
//    is fitted into the flight envelope (rt/rope/envelope_fit.hpp) and judged
//    by rt::PathChecker: exact sight lines and limits on the finest terrain.
//    The answer is the best of them: every requirement met first, then the
//    least violation, then F_c. So the rope never makes the start worse, and
//    a constraint is never traded for F_c. A path better than the best
//    before is kept with its waypoints thinned (rt/rope/waypoint_thinning.hpp:
//    the fit's splits leave runs of vertices on one line; turns near the
//    least radius keep theirs), judged again, unless thinned it meets less or
//    is no longer better than the best before; the answer, if still not
//    thinned, is where that costs under kThinningFcTie of its F_c and leaves
//    it no worse than the start. (The rope is laid on the start as fitted.)
//
// Offline: allocates. `Level` is a sampler level (storage::PackLevel for
// `visvol plan`, DenseLevelView in tests).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fields/dense_level.hpp"
#include "rt/rope/envelope_fit.hpp"
#include "rt/rope/equilibrium.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/global_search.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/point_hull_maker.hpp"
#include "rt/rope/rope.hpp"
#include "rt/rope/slack.hpp"
#include "rt/rope/vehicle.hpp"
#include "rt/rope/waypoint_thinning.hpp"

namespace visvol::rt {

enum class InitialPath : std::uint8_t { straight, global, polyline };

// Rope segments a plan may have (waypoints less one).
inline constexpr int kMaxPlanSegments = 4096;
// Observers of each kind a plan may have: their hulls fold into one a kind
// (detail::ObserverHulls), so the bound is only on the time to build them
// (one hull per observer and level of detail).
inline constexpr int kMaxPlanObservers = 256;
// A level of detail's rope work at most: vertices x time steps. A level runs
// to its simulated-time limit without a wall clock; at about 0.7 us a vertex
// step this keeps one under about half a minute (the default 128 segments
// for 40 s at 1 ms is 5.2e6).
inline constexpr double kMaxVertexStepsPerLevel = 4.0e7;
// The smallest time step the planner takes for stability (the console's 1 kHz
// step); the bound on a level's work counts steps of this length.
inline constexpr double kMinPlanStep_s = 0.001;

struct PlanRequest {
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Objective objective = Objective::hide;
  RopeModel model = RopeModel::articulated;
  int segments = 128;
  InitialPath init = InitialPath::straight;
  std::vector<Vec3> polyline;                       // init == polyline: the path (already lifted if it was 2D)
  VehicleEnvelope envelope;                         // clearance, ceiling, climb, descent, turns
  std::vector<ConstraintPoint> constraints;         // hidden from / visible to observers
  std::optional<fields::Bounds2D> planning_bounds;  // the pack's trusted region
  double curvature_coeff = 0;                       // the pack's Earth curvature and refraction, for the sight lines
  double visibility_gain = 1.0;                     // |k1|; its sign comes from the objective
  double terrain_gain = 1.0;                        // k2
  double stiffness = 1.0;                           // scales the rope's springs
  // Articulated: extra length over the initial path; negative means the
  // default: 0.3 for a straight start, 0.05 for a path that already wanders.
  double slack = -1.0;
  double length_weight = 0.0;  // global search: cost per metre on top of F_p
  // Time step at most (the planner takes less where the rope's springs or
  // the clearance push need it: stable_step_s). Offline there is no 1 kHz
  // loop to keep: 4 ms settles the same paths as 1 ms (visvol-planbench, same
  // F_c to 4 digits, same simulated time to equilibrium, measured before the
  // rope settled by FIRE, whose constants are per step; planner_test's
  // TheStepDoesNotChangeTheAnswer checks the paths still agree), a quarter the work.
  double dt_s = 0.004;
  double max_seconds_per_level = 40.0;
  double candidate_interval_s = 0.25;       // rope states judged this often on the finest level
  std::size_t max_search_voxels = 8000000;  // the finest level the global search may run on
  int fc_samples = 256;
  // Waypoints of each fitted path dropped where the path stays within this of
  // them (none: every fitted vertex kept).
  std::optional<ThinningTolerance> thinning = ThinningTolerance{};
  // Fly the answer as a PX4 fixed-wing would (PathChecker::fly, a report in
  // PlanResult::final_flown): every flight's clearance, and about a check's
  // work for each flight reported.
  bool report_flights = false;
};

Status validate(const PlanRequest& request);

struct PlanProgress {
  int level = 0;  // level of detail being refined
  double simulated_s = 0;
  double fc = 0;                 // on that level
  double rms_speed_m_per_s = 0;  // of the rope's vertices
  const Vec3* vertices = nullptr;
  int vertex_count = 0;
};

struct PlanResult {
  std::vector<Vec3> initial_path, final_path, global_path;
  PathMetrics initial, final_metrics, global;  // all on the finest level
  PathCheck initial_check, final_check;        // exact, on the finest terrain
  std::vector<FlownCheck> final_flown;         // the answer flown (PlanRequest::report_flights)
  bool has_global = false;
  int global_level = -1;     // the level the kept global search ran on
  int first_level = -1;      // the level the rope settled on first (then every finer one)
  std::string chosen;        // which path is the answer: "start", "global search", "rope"
  int candidates = 0;        // paths judged
  int fitted_waypoints = 0;  // the answer's vertices as fitted, before thinning
  double simulated_s = 0;    // all levels
  double equilibrium_s = 0;  // on the finest level, until equilibrium
  bool converged = false;    // the finest level reached equilibrium
  bool diverged = false;     // the rope's state stopped being finite (the best path before stands)
  double wall_s = 0;
  double rope_length_m = 0;
  double max_energy_j = 0;  // largest kinetic energy seen (stability)
};

// The rope's physical parameters for a segment length, sized against the
// field's reference acceleration (stiffness scales the springs).
RopeParams scaled_rope_params(RopeModel model, int segments, double segment_m, double stiffness, double accel_ref);

// The largest time step that keeps a rope of `p` well resolved in a field of
// reference acceleration `accel_ref` (m/s^2, times the largest gain) with a
// clearance push ramping over `clearance_margin_m`: 0.4/omega of the stiffest
// of a chain's highest spring mode and the push, about a third of the limit
// (about 1.1/omega with the rope's explicit damping).
double stable_step_s(const RopeParams& p, double accel_ref, double clearance_margin_m);

// `polyline` lengthened to `length_m` by lifting it along a half sine: a
// rope laid over the synthetic fields of tests and benches. Plans on real
// terrain use lay_with_slack (sideways, above the ground, inside the field).
std::vector<Vec3> with_slack(const std::vector<Vec3>& polyline, double length_m);

// Points of the slack rope as laid (the rope resamples them to its segments).
inline constexpr int kLaidSegments = 128;

// The planner's articulated rope: FIRE's share and the viscous damping (1/s)
// left beside it (the console's rope: none and 6 /s).
inline constexpr double kPlanFireMixing = 0.1;
inline constexpr double kPlanFireDamping_per_s = 0.2;

namespace detail {

// The ends of a request: inside the pack and its planning bounds, above the
// finest terrain and inside the envelope's band of heights there.
Status check_ends(const PlanRequest& request, const PathChecker& checker, double top_m);

// Is path a (its check) better than path b? All met first; then the least
// violation of the envelope and the bounds, then of the constraint points;
// then F_c.
bool better(const PathCheck& a, const PathCheck& b, Objective objective);

// Every observer of a kind on one level as a single hull: a path must stay
// under every hidden-from hull (so under their lowest) and over every
// visible-to hull (so over their highest). Folded post by post, the hull is
// exact at the posts; between them its bilinear height is the more cautious
// one. So any number of observers costs two hulls of memory and one lookup a
// query; building costs one hull per observer.
struct ObserverHulls {
  std::optional<PointHull> hidden_from, visible_to;
  // The hull of a kind as the forces, the fit and the search take it (none or one).
  std::vector<const PointHull*> of(ConstraintKind kind) const;
};

// The folded hulls of `constraints` on a level, each eye lifted onto that
// level's terrain where the level is coarser (and higher) than the finest.
template <class Level>
Result<ObserverHulls> observer_hulls(const Level& level, const std::vector<ConstraintPoint>& constraints) {
  ObserverHulls out;
  if (constraints.empty()) return out;
  const PointHullMaker make(level);  // the level's terrain padded once for all of them
  for (const ConstraintPoint& c : constraints) {
    const bool hidden = c.kind == ConstraintKind::hidden_from;
    Result<PointHull> h = make(eye_on_level(level, c.eye_m()), hidden ? "--hidden-from" : "--visible-to");
    if (!h.ok()) return h.status();
    std::optional<PointHull>& folded = hidden ? out.hidden_from : out.visible_to;
    if (folded) {
      fold_hull(*folded, *h, hidden);
    } else {
      folded = std::move(*h);
    }
  }
  return out;
}

}  // namespace detail

template <class Level>
Result<PlanResult> plan(const std::vector<const Level*>& levels, const PlanRequest& request,
                        const std::function<void(const PlanProgress&)>& on_progress = {}) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  VISVOL_RETURN_IF_ERROR(validate(request));
  if (levels.empty()) return invalid_argument("plan: no levels of detail");
  const Level& finest = *levels.front();
  const VehicleEnvelope& envelope = request.envelope;
  const double top_m = finest.geometry().top_m();

  ForceGains gains;
  gains.k1_visibility = (request.objective == Objective::hide ? -1.0 : 1.0) * request.visibility_gain;
  gains.k2_terrain = request.terrain_gain;
  gains.clearance_m = envelope.clearance_m;
  gains.max_agl_m = envelope.max_agl_m;
  gains.max_altitude_m = std::min(envelope.max_altitude_m, top_m);
  // one environment and the observers' folded hulls, per level
  std::vector<std::unique_ptr<FieldForces<Level>>> envs;
  std::vector<detail::ObserverHulls> hulls(levels.size());
  for (std::size_t l = 0; l < levels.size(); ++l) {
    envs.push_back(std::make_unique<FieldForces<Level>>(*levels[l], gains));
    if (request.planning_bounds) envs.back()->set_bounds(*request.planning_bounds);
    Result<detail::ObserverHulls> h = detail::observer_hulls(*levels[l], request.constraints);
    if (!h.ok()) return h.status();
    hulls[l] = std::move(*h);
    const auto hidden = hulls[l].of(ConstraintKind::hidden_from);
    const auto visible = hulls[l].of(ConstraintKind::visible_to);
    envs.back()->set_hidden_from(hidden.data(), static_cast<int>(hidden.size()));
    envs.back()->set_visible_to(visible.data(), static_cast<int>(visible.size()));
  }
  const FieldForces<Level>& judge = *envs.front();  // metrics on the finest level

  PathCheckSpec spec;
  spec.envelope = envelope;
  spec.constraints = request.constraints;
  spec.planning_bounds = request.planning_bounds;
  spec.curvature_coeff = request.curvature_coeff;
  Result<PathChecker> checker = PathChecker::create(level_terrain(finest), &judge, spec);
  if (!checker.ok()) return checker.status();
  VISVOL_RETURN_IF_ERROR(detail::check_ends(request, *checker, top_m));

  EnvelopeFitSpec fit;
  fit.envelope = envelope;
  fit.planning_bounds = request.planning_bounds;
  fit.top_m = top_m;
  fit.below = hulls.front().of(ConstraintKind::hidden_from);
  fit.above = hulls.front().of(ConstraintKind::visible_to);

  PlanResult result;
  std::vector<Vec3> best;
  PathCheck best_check;
  PathCheck last_check;  // of the path considered last
  // Fits a path into the envelope, judges it, keeps it when it is the best;
  // true when it was kept.
  int best_fitted = 0;               // vertices of the best path as fitted
  std::vector<Vec3> best_as_fitted;  // and those vertices (the rope is laid on them: thinning moved nothing)
  bool best_thinned = false;
  // A fitted path with the waypoints its shape does not need dropped (turns
  // near the least radius keep theirs).
  auto thinned_of = [&](const std::vector<Vec3>& fitted) {
    const LegTest held = held_legs(fitted, envelope, checker->terrain());
    return thin_for_vehicle(fitted, envelope.min_turn_radius_m, *request.thinning, &held);
  };
  auto consider = [&](const Vec3* v, int count, const char* source) {
    EnvelopeFit f = fit_to_envelope(std::vector<Vec3>(v, v + count), fit, checker->terrain());
    last_check = checker->check(f.path);
    ++result.candidates;
    if (!best.empty() && !detail::better(last_check, best_check, request.objective)) return false;
    const int fitted = static_cast<int>(f.path.size());
    std::vector<Vec3> path = f.path;
    if (request.thinning) {
      // the better path's waypoints thinned, unless that meets less (a leg may
      // cross what its vertices avoided) or loses its place to the best before
      std::vector<Vec3> thinned = thinned_of(f.path);
      if (thinned.size() < f.path.size()) {
        PathCheck thinned_check = checker->check(thinned);
        if (!meets_less(thinned_check, last_check) &&
            (best.empty() || detail::better(thinned_check, best_check, request.objective))) {
          path = std::move(thinned);
          last_check = std::move(thinned_check);
        }
      }
    }
    best_thinned = path.size() < f.path.size();
    best = std::move(path);
    best_check = last_check;
    best_fitted = fitted;
    best_as_fitted = std::move(f.path);
    result.chosen = source;
    return true;
  };

  // the start
  // the straight line stands for a global search that finds nothing better
  std::vector<Vec3> start_path =
      request.init == InitialPath::polyline ? request.polyline : std::vector<Vec3>{request.from, request.to};
  consider(start_path.data(), static_cast<int>(start_path.size()), "start");
  if (request.init == InitialPath::global) {
    GlobalSearchParams gp;
    gp.objective = request.objective;
    gp.length_weight = request.length_weight;
    gp.clearance_m = envelope.clearance_m;
    gp.max_agl_m = envelope.max_agl_m;
    gp.max_altitude_m = envelope.max_altitude_m;
    gp.max_climb_deg = envelope.max_climb_deg;
    gp.max_descent_deg = envelope.max_descent_deg;
    gp.bounds = request.planning_bounds;
    // The coarsest level (cheap, always), then the finest level small enough
    // to search: its optimum is what the rope must at least match, and it finds
    // corridors the coarse lattice is too blunt for.
    const int coarsest = static_cast<int>(levels.size()) - 1;
    int fine = coarsest;
    for (int l = 0; l < coarsest; ++l) {
      if (levels[static_cast<std::size_t>(l)]->geometry().voxel_count() <= request.max_search_voxels) {
        fine = l;
        break;
      }
    }
    for (int l : {coarsest, fine}) {
      const Level& level = *levels[static_cast<std::size_t>(l)];
      gp.hidden_from = hulls[static_cast<std::size_t>(l)].of(ConstraintKind::hidden_from);
      gp.visible_to = hulls[static_cast<std::size_t>(l)].of(ConstraintKind::visible_to);
      Result<GlobalPath> gpath = global_search(level, request.from, request.to, gp);
      // no lattice path inside the envelope on this level: the others may have one
      if (gpath.ok() && consider(gpath->points.data(), static_cast<int>(gpath->points.size()), "global search")) {
        result.global_path = best;
        result.global_level = l;
        result.has_global = true;
      }
      if (fine == coarsest) break;
    }
  }
  start_path = best_as_fitted;
  result.initial_path = best;
  result.initial_check = best_check;
  result.initial = path_metrics(best.data(), static_cast<int>(best.size()), judge, request.fc_samples,
                                finest.geometry().spacing_m / 2);
  if (result.has_global) result.global = result.initial;

  // the rope, laid on the best start
  double rope_length = polyline_length_m(start_path.data(), static_cast<int>(start_path.size()));
  std::vector<Vec3> laid = start_path;
  if (request.model == RopeModel::articulated) {
    const double slack = request.slack >= 0 ? request.slack : (request.init == InitialPath::straight ? 0.3 : 0.05);
    rope_length *= 1.0 + slack;
    std::vector<Vec3> base(static_cast<std::size_t>(kLaidSegments) + 1);
    VISVOL_RETURN_IF_ERROR(
        resample_polyline(start_path.data(), static_cast<int>(start_path.size()), kLaidSegments, base.data()));
    laid.resize(base.size());
    const double floor_m = envelope.clearance_m + 20.0;
    // A straight start bows out once; a planned one wiggles in place, a full
    // wave every eight rope segments.
    const int half_waves = request.init == InitialPath::straight ? 1 : std::max(1, request.segments / 4);
    rope_length = lay_with_slack([&](int i) { return base[static_cast<std::size_t>(i)]; }, kLaidSegments, half_waves,
                                 rope_length, floor_m, finest.geometry(),
                                 [&](double x, double y) { return judge.terrain_height_m(x, y); }, laid.data());
  }
  RopeParams rp = scaled_rope_params(request.model, request.segments, rope_length / request.segments, request.stiffness,
                                     judge.reference_acceleration());
  if (request.model == RopeModel::articulated) {
    // Offline, the rope need only come to rest: FIRE with little viscous drag
    // settles the same paths in a quarter fewer steps (tools/bench/README.md,
    // "Plans", stop 31).
    rp.fire_mixing = kPlanFireMixing;
    rp.linear_damping_per_s = rp.angular_damping_per_s = kPlanFireDamping_per_s;
  }
  Result<std::unique_ptr<Rope>> made = make_rope(rp);
  if (!made.ok()) return made.status();
  Rope& rope = **made;
  RopeEnds ends;
  ends.start_m = request.from;
  ends.end_m = request.to;
  rope.set_ends(ends);
  VISVOL_RETURN_IF_ERROR(rope.reset(laid.data(), static_cast<int>(laid.size()), request.segments));
  rope.set_ends(ends);
  result.rope_length_m = rope.length_m();

  // coarse to fine, at a step the stiffest level takes
  double accel_ref = 0;
  for (const auto& e : envs) accel_ref = std::max(accel_ref, e->reference_acceleration());
  // the field's pushes grow with its gains
  const double gain = std::max({1.0, std::fabs(gains.k1_visibility), gains.k2_terrain});
  const double stable = stable_step_s(rp, gain * accel_ref, std::max(0.2 * envelope.clearance_m, 1.0));
  const double dt = std::min(request.dt_s, std::max(stable, kMinPlanStep_s));
  const int steps_per_check = std::max(1, static_cast<int>(std::lround(0.02 / dt)));
  const int checks_per_candidate =
      std::max(1, static_cast<int>(std::lround(request.candidate_interval_s / (steps_per_check * dt))));
  // Coarse to fine from the level the start was found on: a start found on a
  // finer level is already that level's optimum, and a coarser field only
  // drags it to a coarser one that the finer level must then undo.
  result.first_level = result.has_global ? result.global_level : static_cast<int>(levels.size()) - 1;
  for (int level = result.first_level; level >= 0; --level) {
    const FieldForces<Level>& env = *envs[static_cast<std::size_t>(level)];
    const double spacing = levels[static_cast<std::size_t>(level)]->geometry().spacing_m;
    EquilibriumCriteria criteria;
    criteria.check_interval_s = steps_per_check * dt;
    criteria.max_rms_speed_m_per_s = 0.1 * spacing;
    EquilibriumDetector equilibrium(criteria);
    double level_s = 0;
    bool settled = false;
    for (int check = 1; level_s < request.max_seconds_per_level; ++check) {
      for (int s = 0; s < steps_per_check; ++s) rope.step(dt, env);
      level_s += steps_per_check * dt;
      const double ke = rope.kinetic_energy_j();
      result.max_energy_j = std::max(result.max_energy_j, ke);
      const double rms = std::sqrt(2.0 * ke / (rp.mass_kg * (rope.segments() + 1)));
      const double fc = path_fc(rope.vertices(), rope.segments() + 1, env, request.fc_samples);
      if (!std::isfinite(fc) || !std::isfinite(ke)) {
        result.diverged = true;  // the best path seen so far stands
        break;
      }
      if (on_progress)
        on_progress({level, result.simulated_s + level_s, fc, rms, rope.vertices(), rope.segments() + 1});
      if (level == 0 && check % checks_per_candidate == 0) consider(rope.vertices(), rope.segments() + 1, "rope");
      if (equilibrium.add(rms, fc)) {
        settled = true;
        break;
      }
    }
    result.simulated_s += level_s;
    if (result.diverged) break;
    consider(rope.vertices(), rope.segments() + 1, "rope");
    if (level == 0) {
      result.converged = settled;
      result.equilibrium_s = level_s;
    }
  }
  if (request.thinning && !best_thinned) {
    // The answer beat the best before by an F_c its thinned self may not: it
    // is thinned all the same where that meets as much, costs F_c under
    // kThinningFcTie of it, and stays no worse than the start.
    std::optional<ThinnedPath> thinned =
        thinned_as_good(best_as_fitted, best_check, *checker, request.objective, *request.thinning);
    if (thinned && !detail::better(result.initial_check, thinned->check, request.objective)) {
      best = std::move(thinned->path);
      best_check = std::move(thinned->check);
    }
  }
  result.final_path = best;
  result.final_check = std::move(best_check);
  if (request.report_flights) result.final_flown = checker->fly(result.final_path);
  result.fitted_waypoints = best_fitted;
  result.final_metrics = path_metrics(result.final_path.data(), static_cast<int>(result.final_path.size()), judge,
                                      request.fc_samples, finest.geometry().spacing_m / 2);
  result.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace visvol::rt

// The templates a caller of plan() instantiates for one level type, declared
// (KIND extern) or defined (KIND empty): one list, so that a declaration and
// its definition cannot drift apart.
#define VISVOL_PLANNER_TEMPLATES(KIND, LEVEL)                                                                 \
  KIND template class visvol::fields::FieldSampler<LEVEL>;                                                    \
  KIND template class visvol::rt::FieldForces<LEVEL>;                                                         \
  KIND template visvol::Result<visvol::rt::GlobalPath> visvol::rt::global_search<LEVEL>(                      \
      const LEVEL&, const visvol::rt::Vec3&, const visvol::rt::Vec3&, const visvol::rt::GlobalSearchParams&); \
  KIND template visvol::Result<visvol::rt::PlanResult> visvol::rt::plan<LEVEL>(                               \
      const std::vector<const LEVEL*>&, const visvol::rt::PlanRequest&,                                       \
      const std::function<void(const visvol::rt::PlanProgress&)>&);

// Compiled once, optimised, in visvol_rope (plan_dense.cpp) for the levels held
// in memory (tests, benchmarks): each caller instantiated the planner, the
// search and the field's forces again, the longest compile of the tests. (The
// fuzz build has no rope: it leaves plan_dense.cpp out.)
#ifndef VISVOL_FUZZING
VISVOL_PLANNER_TEMPLATES(extern, visvol::fields::DenseLevel)
#endif
