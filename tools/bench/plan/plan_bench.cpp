// visvol-planbench: the planner's speed and quality (issue 13, "Speed and
// quality"), one printed row per plan and a summary.
//
// Terrains, all built in memory: a crop of SF North (the planner tests' crop
// and Fig. 10 observers), a window of the Taunus DEM (the rope bench's) and
// seeded reliefs whose hidden corridor is built and proven with exact sight
// lines before planning. Every plan starts from the global search, with the
// articulated rope and the planner's defaults (128 segments, 40 s a level).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "base/cli_numbers.hpp"
#include "base/version.hpp"
#include "fields/dense_level.hpp"
#include "fields/gdal/dem_io.hpp"
#include "rt/rope/planner.hpp"

namespace {

using namespace visvol;
using namespace visvol::rt;
using fields::DenseLevel;
using Clock = std::chrono::steady_clock;

struct Options {
  int seeds = 8;
  bool quick = false;
  double max_agl_m = 150.0;
  std::string vehicle = "fixed-wing";
};

// How a terrain's levels of detail are built.
struct LevelSpec {
  int nz = 64;
  double ceiling_m = 250.0;
  int range_posts = 24;
  int levels = 2;
  double band_offset_m = 60.0;
  int band_levels = 12;
};

// A terrain and its levels of detail, finest first.
struct World {
  std::string name;
  fields::Heightfield terrain;
  std::vector<DenseLevel> levels;
  double build_s = 0;

  std::vector<const DenseLevel*> pointers() const {
    std::vector<const DenseLevel*> out;
    for (const DenseLevel& l : levels) out.push_back(&l);
    return out;
  }
  // The point agl_m above the terrain at post coordinates (i, j).
  Vec3 above(double i, double j, double agl_m) const {
    return {terrain.x_of(i), terrain.y_of(j), fields::bilinear_height(terrain, i, j) + agl_m};
  }
  fields::Bounds2D bounds() const {
    return {terrain.x_of(0), terrain.y_of(terrain.ny - 1), terrain.x_of(terrain.nx - 1), terrain.y_of(0)};
  }
};

fields::Heightfield window(const fields::Heightfield& src, int i0, int j0, int n) {
  fields::Heightfield out;
  out.nx = out.ny = n;
  out.spacing_m = src.spacing_m;
  out.origin_x = src.x_of(i0);
  out.origin_y = src.y_of(j0);
  out.crs_wkt = src.crs_wkt;
  out.height_m.resize(out.size());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) out.at(i, j) = src.at(i0 + i, j0 + j);
  return out;
}

Result<std::unique_ptr<World>> build_world(std::string name, fields::Heightfield hf, const LevelSpec& spec) {
  const auto t0 = Clock::now();
  fields::FieldParams fp;
  fp.nz = spec.nz;
  fp.ceiling_m = spec.ceiling_m;
  fp.range_posts = spec.range_posts;
  fields::TffParams tp;
  tp.band_offset_m = spec.band_offset_m;
  tp.band_levels = spec.band_levels;
  Result<std::vector<DenseLevel>> levels = fields::build_dense_levels(hf, fp, spec.levels, tp);
  if (!levels.ok()) return levels.status();
  auto w = std::make_unique<World>();
  w->name = std::move(name);
  w->terrain = std::move(hf);
  w->levels = std::move(*levels);
  w->build_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const fields::VolumeGeometry& g = w->levels[0].geometry();
  std::printf(
      "%-10s %d x %d posts of %.0f m, %d levels %.1f m apart, cube range %d posts, %d levels of detail, "
      "built in %.1f s\n",
      w->name.c_str(), g.nx, g.ny, g.spacing_m, g.nz, g.dz_m, spec.range_posts, spec.levels, w->build_s);
  return w;
}

// ---- cases ----------------------------------------------------------------

struct Case {
  std::string name;
  const World* world = nullptr;
  PlanRequest request;
  std::string constraints;    // as printed
  bool reference_ok = false;  // a reference path of ours met every requirement (exact check)
};

PlanRequest base_request(const World& w, const VehicleEnvelope& envelope, Objective objective, Vec3 from, Vec3 to) {
  PlanRequest r;
  r.from = from;
  r.to = to;
  r.objective = objective;
  r.model = RopeModel::articulated;
  r.init = InitialPath::global;
  r.segments = 128;
  r.envelope = envelope;
  r.planning_bounds = w.bounds();
  return r;
}

std::string clearance_text(const VehicleEnvelope& e) {
  char text[64];
  std::snprintf(text, sizeof text, "clearance %.0f m", e.clearance_m);
  return text;
}

std::string ceiling_text(double max_agl_m) {
  char text[64];
  std::snprintf(text, sizeof text, "max-agl %.0f m", max_agl_m);
  return text;
}

// Ends above the terrain: the given height, or lower to fit under a ceiling.
double end_agl_m(double wanted_m, const VehicleEnvelope& e) {
  return std::isfinite(e.max_agl_m) ? std::min(wanted_m, 0.5 * (e.clearance_m + e.max_agl_m)) : wanted_m;
}

// SF North, the planner tests' crop: hide, Fig. 10 observers, show under a ceiling.
std::vector<Case> sf_north_cases(const World& w, const VehicleEnvelope& envelope, const Options& o) {
  std::vector<Case> cases;
  const Vec3 from = w.above(8, 8, 40), to = w.above(87, 87, 40);
  if (!o.quick)
    cases.push_back(
        {w.name, &w, base_request(w, envelope, Objective::hide, from, to), clearance_text(envelope), false});
  // observers on the ground, eyes 2 m up: p1 on a hill east of the route, p2 in the north-east
  Case fig10{w.name, &w, base_request(w, envelope, Objective::hide, from, to), "hidden-from p1, visible-to p2", false};
  fig10.request.constraints = {{ConstraintKind::hidden_from, w.above(64, 78, 0), 2.0},
                               {ConstraintKind::visible_to, w.above(88, 24, 0), 2.0}};
  cases.push_back(fig10);
  if (!o.quick) {
    VehicleEnvelope ceiling = envelope;
    ceiling.max_agl_m = o.max_agl_m;
    const double agl = end_agl_m(40, ceiling);
    cases.push_back({w.name, &w, base_request(w, ceiling, Objective::show, w.above(8, 8, agl), w.above(87, 87, agl)),
                     ceiling_text(o.max_agl_m), false});
  }
  return cases;
}

// The Taunus window and the rope bench's end posts: hide, show under a ceiling.
std::vector<Case> taunus_cases(const World& w, const VehicleEnvelope& envelope, const Options& o) {
  std::vector<Case> cases;
  cases.push_back({w.name, &w, base_request(w, envelope, Objective::hide, w.above(20, 30, 100), w.above(235, 220, 100)),
                   clearance_text(envelope), false});
  VehicleEnvelope ceiling = envelope;
  ceiling.max_agl_m = o.max_agl_m;
  const double agl = end_agl_m(100, ceiling);
  cases.push_back({w.name, &w, base_request(w, ceiling, Objective::show, w.above(20, 30, agl), w.above(235, 220, agl)),
                   ceiling_text(o.max_agl_m), false});
  return cases;
}

// ---- seeded reliefs -------------------------------------------------------
//
// A sum of Gaussian hills on a flat base, 80 x 80 posts of 30 m:
//   - a ridge running west-east (row 24);
//   - a ground observer on a peak north of it (row 6), high enough that the
//     ridge's shadow reaches down into the valley south of it, where the
//     ends lie (rows 46-52), but not too far: the shadow's height there is
//     chosen 15-35 m above the corridor the reference flies;
//   - small hills in the south;
//   - a blocker hill on the straight line between the ends, its top 30-60 m
//     above the shadow: over it a path is seen, so the straight line fails.
// The reference corridor detours north of the blocker (where the shadow is
// higher) at one height: the highest post under it plus the clearance and
// 8 m. Shadows follow from similar triangles, as the ridge is straight.

constexpr int kReliefPosts = 80;
constexpr double kReliefSpacing_m = 30.0;
constexpr double kReliefBase_m = 20.0;
constexpr double kRidgeRow = 24.0;
constexpr double kObserverRow = 6.0;

struct Bump {
  double ci = 0, cj = 0;  // centre, posts
  double amplitude_m = 0;
  double sigma_i = 1, sigma_j = 1;  // posts
  double at(double i, double j) const {
    const double a = (i - ci) / sigma_i, b = (j - cj) / sigma_j;
    return amplitude_m * std::exp(-0.5 * (a * a + b * b));
  }
};

struct Relief {
  fields::Heightfield terrain;
  ConstraintPoint observer;
  std::vector<Vec3> reference;  // ends included
  std::vector<Vec3> straight;   // the ends, for comparison
};

fields::Heightfield relief_terrain(const std::vector<Bump>& bumps) {
  fields::Heightfield hf;
  hf.nx = hf.ny = kReliefPosts;
  hf.spacing_m = kReliefSpacing_m;
  hf.origin_x = 500000.0;  // a local metric frame
  hf.origin_y = 4200000.0;
  hf.height_m.resize(hf.size());
  for (int j = 0; j < hf.ny; ++j) {
    for (int i = 0; i < hf.nx; ++i) {
      double z = kReliefBase_m;
      for (const Bump& b : bumps) z += b.at(i, j);
      hf.at(i, j) = static_cast<float>(z);
    }
  }
  return hf;
}

// The highest post under a plan polyline (posts), sampled every quarter post:
// the bilinear terrain never exceeds the posts around a sample.
double highest_post_under(const fields::Heightfield& hf, const std::vector<Eigen::Vector2d>& plan) {
  double top = -1e30;
  for (std::size_t s = 1; s < plan.size(); ++s) {
    const int n = static_cast<int>(std::ceil(4.0 * (plan[s] - plan[s - 1]).norm()));
    for (int q = 0; q <= n; ++q) {
      const Eigen::Vector2d p = plan[s - 1] + (plan[s] - plan[s - 1]) * (double(q) / n);
      const int i = static_cast<int>(std::floor(p.x())), j = static_cast<int>(std::floor(p.y()));
      for (int dj = 0; dj <= 1; ++dj)
        for (int di = 0; di <= 1; ++di)
          top = std::max(top, double(hf.at(std::clamp(i + di, 0, hf.nx - 1), std::clamp(j + dj, 0, hf.ny - 1))));
    }
  }
  return top;
}

Relief seeded_relief(unsigned seed, double clearance_m) {
  std::mt19937 rng(seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  const double crest_m = uniform(140, 180);
  std::vector<Bump> bumps{{0, kRidgeRow, crest_m, 1e6, uniform(2.5, 3.5)}};
  const int small_hills = 5 + static_cast<int>(rng() % 5);
  for (int h = 0; h < small_hills; ++h) {
    const double sigma = uniform(2, 5);
    bumps.push_back({uniform(0, kReliefPosts - 1), uniform(32, kReliefPosts - 1), uniform(5, 25), sigma, sigma});
  }
  const Eigen::Vector2d a(6, uniform(46, 52)), b(kReliefPosts - 7, uniform(46, 52));
  const double blocker_i = uniform(30, 50), blocker_sigma = uniform(2.5, 3.5);
  const double blocker_j = a.y() + (b.y() - a.y()) * (blocker_i - a.x()) / (b.x() - a.x());
  const double detour_j = blocker_j - 3.5 * blocker_sigma - 1;
  const std::vector<Eigen::Vector2d> plan{
      a, {blocker_i - 3 * blocker_sigma - 2, detour_j}, {blocker_i + 3 * blocker_sigma + 2, detour_j}, b};
  // the shadow's height at the lower end's row, and the eye that casts it
  const double corridor_m = highest_post_under(relief_terrain(bumps), plan) + clearance_m + 8;
  const double ends_row = std::max(a.y(), b.y()) + 0.5;
  const double shadow_m = corridor_m + uniform(15, 35);
  const double crest_top_m = kReliefBase_m + crest_m;
  const double eye_m = crest_top_m + (crest_top_m - shadow_m) * (kRidgeRow - kObserverRow) / (ends_row - kRidgeRow);
  auto shadow_at = [&](double j) {
    return crest_top_m - (eye_m - crest_top_m) * (j - kRidgeRow) / (kRidgeRow - kObserverRow);
  };
  const double observer_i = std::round(uniform(20, 60));
  bumps.push_back({observer_i, kObserverRow, eye_m - 2 - kReliefBase_m, 5, 5});
  bumps.push_back(
      {blocker_i, blocker_j, shadow_at(blocker_j) + uniform(30, 60) - kReliefBase_m, blocker_sigma, blocker_sigma});

  Relief out;
  out.terrain = relief_terrain(bumps);
  const double z_m = highest_post_under(out.terrain, plan) + clearance_m + 8;  // the blocker's skirt included
  for (const Eigen::Vector2d& p : plan)
    out.reference.push_back({out.terrain.x_of(p.x()), out.terrain.y_of(p.y()), z_m});
  out.straight = {out.reference.front(), out.reference.back()};
  const double ground_m = out.terrain.at(static_cast<int>(observer_i), static_cast<int>(kObserverRow));
  out.observer = {
      ConstraintKind::hidden_from, {out.terrain.x_of(observer_i), out.terrain.y_of(kObserverRow), ground_m}, 2.0};
  return out;
}

// ---- the judge ------------------------------------------------------------

Result<PathChecker> make_checker(const World& w, const PlanRequest& r, const FieldForces<DenseLevel>& field) {
  PathCheckSpec spec;
  spec.envelope = r.envelope;
  spec.constraints = r.constraints;
  spec.planning_bounds = r.planning_bounds;
  spec.curvature_coeff = r.curvature_coeff;
  return PathChecker::create(level_terrain(w.levels[0]), &field, spec);
}

// The global search's optimum on the finest lattice, with the plan's
// envelope and constraints; and whether, fitted into the envelope, it meets
// every requirement by the exact check (then a feasible path is known).
struct Optimum {
  bool found = false;
  double fc = 0;           // of the voxel path
  double fitted_fc = 0;    // of it fitted into the envelope
  bool meets_all = false;  // fitted
  double search_s = 0;
};

Result<Optimum> lattice_optimum(const World& w, const PlanRequest& r, const FieldForces<DenseLevel>& field,
                                const PathChecker& checker) {
  const DenseLevel& finest = w.levels[0];
  Result<detail::ObserverHulls> hulls = detail::observer_hulls(finest, r.constraints);
  if (!hulls.ok()) return hulls.status();
  GlobalSearchParams gp;
  gp.objective = r.objective;
  gp.length_weight = r.length_weight;
  gp.clearance_m = r.envelope.clearance_m;
  gp.max_agl_m = r.envelope.max_agl_m;
  gp.max_altitude_m = r.envelope.max_altitude_m;
  gp.max_climb_deg = r.envelope.max_climb_deg;
  gp.max_descent_deg = r.envelope.max_descent_deg;
  gp.bounds = r.planning_bounds;
  gp.hidden_from = hulls->of(ConstraintKind::hidden_from);
  gp.visible_to = hulls->of(ConstraintKind::visible_to);
  Optimum out;
  const auto t0 = Clock::now();
  Result<GlobalPath> g = global_search(finest, r.from, r.to, gp);
  out.search_s = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!g.ok()) return out;  // no lattice path inside the envelope
  out.found = true;
  out.fc = path_fc(g->points.data(), static_cast<int>(g->points.size()), field, r.fc_samples);
  EnvelopeFitSpec fit;
  fit.envelope = r.envelope;
  fit.planning_bounds = r.planning_bounds;
  fit.top_m = finest.geometry().top_m();
  fit.below = gp.hidden_from;
  fit.above = gp.visible_to;
  const PathCheck fitted = checker.check(fit_to_envelope(g->points, fit, checker.terrain()).path);
  out.fitted_fc = fitted.fc;
  out.meets_all = fitted.all_met;
  return out;
}

// ---- running and printing -------------------------------------------------

struct Row {
  const Case* c = nullptr;
  PlanResult plan;
  Optimum optimum;
  bool feasible() const { return c->reference_ok || optimum.meets_all; }  // proven apart from the plan
};

// A figure with `decimals` places, or "n/a" where there is none (NaN).
std::string figure(double v, int decimals) {
  if (std::isnan(v)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

void print_header() {
  std::printf("\n%-10s %-6s %-30s %8s %8s %8s %7s %8s %6s %3s %6s %6s %6s %-4s %-4s %-11s %-13s %s\n", "case", "obj.",
              "constraints", "Fc start", "Fc final", "Fc opt", "fin/opt", "opt fit", "opt ok", "lvl", "eq s", "sim s",
              "wall s", "conv", "met", "feasible", "chosen", "waypoints");
}

const char* feasible_text(const Row& row) {
  if (row.c->reference_ok && row.optimum.meets_all) return "ref+lattice";
  if (row.c->reference_ok) return "ref";
  if (row.optimum.meets_all) return "lattice";
  return "not proven";
}

void print_row(const Row& row) {
  const PlanResult& p = row.plan;
  const Optimum& o = row.optimum;
  const double ratio = o.found && o.fc > 0 ? p.final_metrics.fc / o.fc : std::nan("");
  std::printf("%-10s %-6s %-30s %8.4f %8.4f %8s %7s %8s %6s %3d %6.2f %6.2f %6.2f %-4s %-4s %-11s %-13s %zu of %d\n",
              row.c->name.c_str(), to_string(row.c->request.objective), row.c->constraints.c_str(), p.initial.fc,
              p.final_metrics.fc, figure(o.found ? o.fc : std::nan(""), 4).c_str(), figure(ratio, 3).c_str(),
              figure(o.found ? o.fitted_fc : std::nan(""), 4).c_str(), o.found ? (o.meets_all ? "yes" : "no") : "none",
              p.global_level, p.equilibrium_s, p.simulated_s, p.wall_s, p.converged ? "yes" : "no",
              p.final_check.all_met ? "yes" : "NO", feasible_text(row), p.chosen.c_str(), p.final_path.size(),
              p.fitted_waypoints);
  if (!p.final_check.all_met)
    for (const std::string& u : p.final_check.unmet()) std::printf("           unmet: %s\n", u.c_str());
}

// Plans one case and measures its lattice optimum; false when planning failed.
bool run_case(const Case& c, std::vector<Row>& rows) {
  const Result<PlanResult> res = plan(c.world->pointers(), c.request);
  if (!res.ok()) {
    std::printf("%-10s %-6s %-30s plan failed: %s\n", c.name.c_str(), to_string(c.request.objective),
                c.constraints.c_str(), res.status().message().c_str());
    return false;
  }
  const FieldForces<DenseLevel> field(c.world->levels[0], ForceGains{});
  Result<PathChecker> checker = make_checker(*c.world, c.request, field);
  Result<Optimum> optimum =
      checker.ok() ? lattice_optimum(*c.world, c.request, field, *checker) : Result<Optimum>(checker.status());
  if (!optimum.ok()) {
    std::printf("%-10s lattice optimum failed: %s\n", c.name.c_str(), optimum.status().message().c_str());
    return false;
  }
  rows.push_back({&c, *res, *optimum});
  print_row(rows.back());
  std::fflush(stdout);
  return true;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void print_summary(const std::vector<Row>& rows, int seeds_tried, int seeds_verified) {
  int feasible = 0, feasible_met = 0, other = 0, other_met = 0, converged = 0;
  std::vector<double> eq_s, wall_s, search_s, hide_ratio, show_ratio;
  for (const Row& r : rows) {
    const bool met = r.plan.final_check.all_met;
    (r.feasible() ? feasible : other) += 1;
    (r.feasible() ? feasible_met : other_met) += met ? 1 : 0;
    converged += r.plan.converged ? 1 : 0;
    eq_s.push_back(r.plan.equilibrium_s);
    wall_s.push_back(r.plan.wall_s);
    search_s.push_back(r.optimum.search_s);
    std::vector<double>& ratios = r.c->request.objective == Objective::hide ? hide_ratio : show_ratio;
    if (r.optimum.found && r.optimum.fc > 0) ratios.push_back(r.plan.final_metrics.fc / r.optimum.fc);
  }
  std::printf("\nseeded reliefs: %d of %d references proven feasible by exact sight lines (the others not planned)\n",
              seeds_verified, seeds_tried);
  std::printf(
      "runs with a feasible path proven apart from the plan: %d; meeting every requirement: %d "
      "(%.0f%%; goal: all)\n",
      feasible, feasible_met, feasible ? 100.0 * feasible_met / feasible : 0.0);
  std::printf("runs with no such proof: %d; meeting every requirement: %d\n", other, other_met);
  std::printf(
      "equilibrium on the finest level: median %.2f simulated s (goal <= 2 s; the paper 3-4 s); "
      "%d of %zu runs converged (the others count at their %.0f s cap)\n",
      median(eq_s), converged, rows.size(), PlanRequest{}.max_seconds_per_level);
  std::printf("wall time of a whole plan: median %.2f s, longest %.2f s\n", median(wall_s),
              wall_s.empty() ? 0.0 : *std::max_element(wall_s.begin(), wall_s.end()));
  std::printf("finest-lattice search alone (for Fc opt): median %.2f s, longest %.2f s\n", median(search_s),
              search_s.empty() ? 0.0 : *std::max_element(search_s.begin(), search_s.end()));
  std::printf("final F_c / lattice optimum: median %s hiding (under 1 beats it), %s showing (over 1 beats it)\n",
              figure(median(hide_ratio), 3).c_str(), figure(median(show_ratio), 3).c_str());
}

// ---- the seeded cases -----------------------------------------------------

// Builds seed's relief, proves its reference corridor, and adds its case
// when the proof holds; false when a build failed.
bool add_seed_case(unsigned seed, const VehicleEnvelope& envelope, std::vector<std::unique_ptr<World>>& worlds,
                   std::vector<Case>& cases) {
  Relief relief = seeded_relief(seed, envelope.clearance_m);
  const std::string name = "relief " + std::to_string(seed);
  Result<std::unique_ptr<World>> w = build_world(name, relief.terrain, LevelSpec{64, 150.0, 24, 2, 60.0, 12});
  if (!w.ok()) {
    std::printf("%s: build failed: %s\n", name.c_str(), w.status().message().c_str());
    return false;
  }
  Case c{name, w->get(),
         base_request(**w, envelope, Objective::hide, relief.reference.front(), relief.reference.back()),
         "hidden-from ridge observer", false};
  c.request.constraints = {relief.observer};
  const FieldForces<DenseLevel> field((*w)->levels[0], ForceGains{});
  Result<PathChecker> checker = make_checker(**w, c.request, field);
  if (!checker.ok()) {
    std::printf("%s: %s\n", name.c_str(), checker.status().message().c_str());
    return false;
  }
  // the straight line as the planner would fly it: lifted over the blocker by the envelope
  EnvelopeFitSpec fit;
  fit.envelope = envelope;
  fit.planning_bounds = c.request.planning_bounds;
  fit.top_m = (*w)->levels[0].geometry().top_m();
  const PathCheck ref = checker->check(relief.reference);
  const PathCheck straight = checker->check(fit_to_envelope(relief.straight, fit, checker->terrain()).path);
  c.reference_ok = ref.all_met;
  std::printf(
      "           reference corridor at %.0f m: %s (hidden %.3f of its length, F_c %.4f); straight line "
      "in the envelope: hidden %.3f\n",
      relief.reference.front().z(), ref.all_met ? "every requirement met" : "NOT feasible",
      ref.constraints[0].satisfied_fraction, ref.fc, straight.constraints[0].satisfied_fraction);
  for (const std::string& u : ref.unmet()) std::printf("           unmet: %s\n", u.c_str());
  worlds.push_back(std::move(*w));
  if (c.reference_ok) cases.push_back(std::move(c));
  return true;
}

// ---- main -----------------------------------------------------------------

const char* kFooter = R"(What is printed, one row per plan (global start, articulated rope, 128 segments):
  case, obj.    terrain and objective (hide: least seen; show: most seen)
  constraints   beyond the vehicle envelope (every plan also keeps its clearance, climb, descent and turns)
  Fc start      F_c (importance-weighted mean F_p along the path, dimensionless) of the planner's start
  Fc final      F_c of the planner's answer
  Fc opt        F_c of the global search's optimum on the finest lattice with the same envelope and constraints
  fin/opt       Fc final / Fc opt (hiding: under 1 beats the lattice; showing: over 1 does)
  opt fit       F_c of that optimum fitted into the envelope (the planner's fit: flyable turns and slopes)
  opt ok        that fitted optimum meets every requirement (exact check)
  lvl           level of detail of the global start the planner kept (0 finest, -1 none)
  eq s          simulated seconds on the finest level until equilibrium (the cap when not converged)
  sim s         simulated seconds on all levels
  wall s        wall-clock seconds of the whole plan (search, rope, checks)
  conv, met     the finest level reached equilibrium; the answer meets every requirement (exact sight lines)
  feasible      how a feasible path is known apart from the plan: ref (our corridor), lattice, or not proven
  chosen        the answer: start, global search or rope
  waypoints     the answer's vertices, of those the envelope fit gave it (the
                others thinned away: within 0.5 m across and 0.2 m up or down;
                turns near the least radius keep theirs)
Then the fraction of runs with a proven feasible path meeting every requirement, the median equilibrium
time against the 2 s goal, the median wall time and the median F_c ratios.
Exit status: 0 (also when requirements are unmet: a measurement), 1 when a plan or a build failed, 2 for bad
options.)";

// Returns -1 to go on, or the exit status: 0 after --help, 2 for a bad option.
int parse_options(int argc, char** argv, Options& o) {
  CLI::App app{"visvol-planbench: the planner's speed and quality on SF North, the Taunus window and seeded reliefs"};
  app.set_version_flag("--version",
                       visvol::version_line("visvol-planbench"));  // listed in --help; handled first in main
  app.add_option("--seeds", o.seeds, "Seeded reliefs to plan on")->check(CLI::Range(0, 1000))->capture_default_str();
  app.add_flag("--quick", o.quick, "A smoke run: the SF North Fig. 10 case and at most one seed, no Taunus");
  app.add_option("--max-agl", o.max_agl_m, "Ceiling of the show cases, m above the terrain")
      ->check(CLI::Range(60.0, 2000.0))
      ->capture_default_str();
  app.add_option("--vehicle", o.vehicle, "Vehicle preset")
      ->check(CLI::IsMember({"fixed-wing", "multirotor"}))
      ->capture_default_str();
  app.footer(kFooter);
  visvol::decimal_numbers(app);  // "010" is ten, not octal eight
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);            // --help
    std::fprintf(stderr, "visvol-planbench: %s\n", e.what());  // CLI11 names the option
    return 2;
  }
  return -1;
}

// A square window of a bundled DEM and its levels.
Result<std::unique_ptr<World>> dem_world(const std::string& name, const std::string& file, int i0, int j0, int n,
                                         const LevelSpec& spec) {
  Result<fields::Heightfield> dem =
      fields::read_heightfield(std::string(VISVOL_TEST_DATA) + "/" + file, {fields::NodataPolicy::fill});
  if (!dem.ok()) return dem.status();
  return build_world(name, window(*dem, i0, j0, n), spec);
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-planbench")) return 0;
  Options o;
  const int parsed = parse_options(argc, argv, o);
  if (parsed >= 0) return parsed;
  const Result<VehicleEnvelope> envelope = vehicle_preset(o.vehicle);
  if (!envelope.ok()) {
    std::fprintf(stderr, "visvol-planbench: --vehicle %s\n", envelope.status().message().c_str());
    return 2;
  }
  std::printf("vehicle %s: clearance %.0f m, climb %.0f deg, descent %.0f deg, turns of %.0f m or wider%s\n\n",
              envelope->name.c_str(), envelope->clearance_m, envelope->max_climb_deg, envelope->max_descent_deg,
              envelope->min_turn_radius_m, o.quick ? "; --quick" : "");

  std::vector<std::unique_ptr<World>> worlds;
  std::vector<Case> cases;
  Result<std::unique_ptr<World>> sf = dem_world("sf-north", "sf_north_utm10_30m.tif", 150, 250, 96, LevelSpec{});
  if (!sf.ok()) {
    std::fprintf(stderr, "visvol-planbench: SF North: %s\n", sf.status().message().c_str());
    return 1;
  }
  worlds.push_back(std::move(*sf));
  for (Case& c : sf_north_cases(*worlds.back(), *envelope, o)) cases.push_back(std::move(c));
  if (!o.quick) {
    Result<std::unique_ptr<World>> taunus =
        dem_world("taunus", "taunus_utm32n_90m_512.tif", 128, 128, 256, LevelSpec{96, 300.0, 32, 3, 100.0, 24});
    if (!taunus.ok()) {
      std::fprintf(stderr, "visvol-planbench: Taunus: %s\n", taunus.status().message().c_str());
      return 1;
    }
    worlds.push_back(std::move(*taunus));
    for (Case& c : taunus_cases(*worlds.back(), *envelope, o)) cases.push_back(std::move(c));
  }
  const int seeds = o.quick ? std::min(o.seeds, 1) : o.seeds;
  const std::size_t before = cases.size();
  for (int s = 1; s <= seeds; ++s)
    if (!add_seed_case(static_cast<unsigned>(s), *envelope, worlds, cases)) return 1;
  const int verified = static_cast<int>(cases.size() - before);

  print_header();
  std::vector<Row> rows;
  bool failed = false;
  for (const Case& c : cases) failed = !run_case(c, rows) || failed;
  print_summary(rows, seeds, verified);
  return failed ? 1 : 0;
}
