// The offline planner: a rope from A to B settles in the field, coarse level
// of detail first, then the finer ones (coarse-to-fine continuation), until it
// reaches equilibrium on the finest.
//
// Initial paths: the straight segment, a polyline (a 2D one lifted to the
// clearance above the terrain, or a 3D one), or the global graph search on the
// coarsest level. An inextensible (articulated) rope needs slack to move: it is
// `slack` longer than its initial path, bent sideways (rt/rope/slack.hpp).
//
// Equilibrium: over the last half second, the rope's RMS speed stays under a
// tenth of a post spacing per second and F_c changes by less than 0.2% of
// itself per second (plus 1e-6): what is left is a slow creep along a flat
// ridge of the objective that no longer changes F_c.
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

#include "rt/rope/equilibrium.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/global_search.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/rope.hpp"
#include "rt/rope/slack.hpp"

namespace visvol::rt {

enum class InitialPath : std::uint8_t { straight, global, polyline };

struct PlanRequest {
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Objective objective = Objective::hide;
  RopeModel model = RopeModel::articulated;
  int segments = 128;
  InitialPath init = InitialPath::straight;
  std::vector<Vec3> polyline;       // init == polyline: the path (already lifted if it was 2D)
  std::optional<Vec3> hidden_from;  // stay hidden from this point
  std::optional<Vec3> visible_to;   // stay visible to this point
  double clearance_m = 30.0;
  double visibility_gain = 1.0;     // |k1|; its sign comes from the objective
  double terrain_gain = 1.0;        // k2
  double stiffness = 1.0;           // scales the rope's springs
  // Articulated: extra length over the initial path; negative means the
  // default: 0.3 for a straight start, 0.05 for a path that already wanders.
  double slack = -1.0;
  double length_weight = 0.0;       // global search: cost per metre on top of F_p
  double dt_s = 0.001;
  double max_seconds_per_level = 40.0;
  int fc_samples = 256;
};

Status validate(const PlanRequest& request);

struct PlanProgress {
  int level = 0;               // level of detail being refined
  double simulated_s = 0;
  double fc = 0;               // on that level
  double rms_speed_mps = 0;    // of the rope's vertices
  const Vec3* vertices = nullptr;
  int vertex_count = 0;
};

struct PlanResult {
  std::vector<Vec3> initial_path, final_path, global_path;
  PathMetrics initial, final_metrics, global;  // all on the finest level
  bool has_global = false;
  double simulated_s = 0;      // all levels
  double equilibrium_s = 0;    // on the finest level, until equilibrium
  bool converged = false;      // the finest level reached equilibrium
  double wall_s = 0;
  double rope_length_m = 0;
  double max_energy_j = 0;     // largest kinetic energy seen (stability)
};

// The rope's physical parameters for a segment length, sized against the
// field's reference acceleration (stiffness scales the springs).
RopeParams scaled_rope_params(RopeModel model, int segments, double segment_m, double stiffness,
                              double accel_ref);

// `polyline` lengthened to `length_m` by lifting it along a half sine: a
// rope laid over the synthetic fields of tests and benches. Plans on real
// terrain use lay_with_slack (sideways, above the ground, inside the field).
std::vector<Vec3> with_slack(const std::vector<Vec3>& polyline, double length_m);

// Points of the slack rope as laid (the rope resamples them to its segments).
inline constexpr int kLaidSegments = 128;

template <class Level>
Result<PlanResult> plan(const std::vector<const Level*>& levels, const PlanRequest& request,
                        const std::function<void(const PlanProgress&)>& on_progress = {}) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  VISVOL_RETURN_IF_ERROR(validate(request));
  if (levels.empty()) return invalid_argument("plan: no levels of detail");
  const Level& finest = *levels.front();
  const Level& coarsest = *levels.back();
  for (const Vec3* p : {&request.from, &request.to}) {
    const fields::VolumeGeometry& g = finest.geometry();
    const double x1 = g.origin_x + (g.nx - 1) * g.spacing_m, y0 = g.origin_y - (g.ny - 1) * g.spacing_m;
    const char* name = p == &request.from ? "--from" : "--to";
    if (p->x() < g.origin_x || p->x() > x1 || p->y() < y0 || p->y() > g.origin_y) {
      return invalid_argument(std::string(name) + ": (" + std::to_string(p->x()) + ", " + std::to_string(p->y()) +
                              ") is outside the pack (x " + std::to_string(g.origin_x) + ".." + std::to_string(x1) +
                              ", y " + std::to_string(y0) + ".." + std::to_string(g.origin_y) + ")");
    }
    const double ground = fields::FieldSampler<Level>(finest).height(p->x(), p->y());
    if (p->z() < ground) {
      return invalid_argument(std::string(name) + ": " + std::to_string(ground - p->z()) + " m below the terrain");
    }
  }

  ForceGains gains;
  gains.k1_visibility = (request.objective == Objective::hide ? -1.0 : 1.0) * request.visibility_gain;
  gains.k2_terrain = request.terrain_gain;
  gains.clearance_m = request.clearance_m;
  // one environment (and constraint hulls) per level
  std::vector<std::unique_ptr<FieldForces<Level>>> envs;
  std::vector<PointHull> hulls;
  hulls.reserve(2 * levels.size());
  for (const Level* level : levels) {
    envs.push_back(std::make_unique<FieldForces<Level>>(*level, gains));
    if (request.hidden_from) {
      Result<PointHull> h = point_hull(*level, *request.hidden_from, "--hidden-from");
      if (!h.ok()) return h.status();
      hulls.push_back(std::move(*h));
      envs.back()->set_hidden_from(&hulls.back());
    }
    if (request.visible_to) {
      Result<PointHull> h = point_hull(*level, *request.visible_to, "--visible-to");
      if (!h.ok()) return h.status();
      hulls.push_back(std::move(*h));
      envs.back()->set_visible_to(&hulls.back());
    }
  }
  const FieldForces<Level>& judge = *envs.front();  // metrics on the finest level

  PlanResult result;
  std::vector<Vec3> start_path;
  switch (request.init) {
    case InitialPath::straight: start_path = {request.from, request.to}; break;
    case InitialPath::polyline: start_path = request.polyline; break;
    case InitialPath::global: {
      GlobalSearchParams gp;
      gp.objective = request.objective;
      gp.length_weight = request.length_weight;
      gp.clearance_m = request.clearance_m;
      Result<GlobalPath> gpath = global_search(coarsest, request.from, request.to, gp);
      if (!gpath.ok()) return gpath.status();
      start_path = gpath->points;
      break;
    }
  }
  auto length_of = [](const std::vector<Vec3>& p) {
    double l = 0;
    for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
    return l;
  };
  result.initial_path = start_path;
  result.initial = path_metrics(start_path.data(), static_cast<int>(start_path.size()), judge,
                                request.fc_samples, finest.geometry().spacing_m / 2);
  double rope_length = length_of(start_path);
  std::vector<Vec3> laid = start_path;
  if (request.model == RopeModel::articulated) {
    const double slack = request.slack >= 0 ? request.slack : (request.init == InitialPath::straight ? 0.3 : 0.05);
    rope_length *= 1.0 + slack;
    std::vector<Vec3> base(static_cast<std::size_t>(kLaidSegments) + 1);
    VISVOL_RETURN_IF_ERROR(resample_polyline(start_path.data(), static_cast<int>(start_path.size()), kLaidSegments,
                                             base.data()));
    laid.resize(base.size());
    const double floor_m = request.clearance_m + 20.0;
    // A straight start bows out once; a planned one wiggles in place, a full
    // wave every eight rope segments.
    const int half_waves = request.init == InitialPath::straight ? 1 : std::max(1, request.segments / 4);
    rope_length = lay_with_slack([&](int i) { return base[static_cast<std::size_t>(i)]; }, kLaidSegments,
                                 half_waves, rope_length, floor_m, finest.geometry(),
                                 [&](double x, double y) { return judge.terrain_height_m(x, y); }, laid.data());
  }
  const RopeParams rp = scaled_rope_params(request.model, request.segments, rope_length / request.segments,
                                           request.stiffness, judge.reference_acceleration());
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

  // coarse to fine
  const int steps_per_check = std::max(1, static_cast<int>(std::lround(0.02 / request.dt_s)));
  for (int level = static_cast<int>(levels.size()) - 1; level >= 0; --level) {
    const FieldForces<Level>& env = *envs[static_cast<std::size_t>(level)];
    const double spacing = levels[static_cast<std::size_t>(level)]->geometry().spacing_m;
    EquilibriumCriteria criteria;
    criteria.check_interval_s = steps_per_check * request.dt_s;
    criteria.max_rms_speed_mps = 0.1 * spacing;
    EquilibriumDetector equilibrium(criteria);
    double level_s = 0;
    bool settled = false;
    while (level_s < request.max_seconds_per_level) {
      for (int s = 0; s < steps_per_check; ++s) rope.step(request.dt_s, env);
      level_s += steps_per_check * request.dt_s;
      const double ke = rope.kinetic_energy_j();
      result.max_energy_j = std::max(result.max_energy_j, ke);
      const double rms = std::sqrt(2.0 * ke / (rp.mass_kg * (rope.segments() + 1)));
      const double fc = path_fc(rope.vertices(), rope.segments() + 1, env, request.fc_samples);
      if (!std::isfinite(fc) || !std::isfinite(ke)) {
        return Status(Errc::state, "plan: the rope diverged at level " + std::to_string(level) +
                                       " after " + std::to_string(level_s) + " s; lower the gains");
      }
      if (on_progress) on_progress({level, result.simulated_s + level_s, fc, rms, rope.vertices(), rope.segments() + 1});
      if (equilibrium.add(rms, fc)) {
        settled = true;
        break;
      }
    }
    result.simulated_s += level_s;
    if (level == 0) {
      result.converged = settled;
      result.equilibrium_s = level_s;
    }
  }
  result.final_path.assign(rope.vertices(), rope.vertices() + rope.segments() + 1);
  result.final_metrics = path_metrics(result.final_path.data(), static_cast<int>(result.final_path.size()), judge,
                                      request.fc_samples, finest.geometry().spacing_m / 2);
  if (request.init == InitialPath::global) {
    result.global_path = start_path;
    result.global = result.initial;
    result.has_global = true;
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

}  // namespace visvol::rt
