// visvol-ropebench: what a rope step costs, and how fast ropes settle.
//
// Google Benchmark of one step (field forces included) for 32 to 512 segments
// of both models on a real terrain (a 256 x 256 window of the Taunus DEM,
// range 32, in memory), then printed figures: simulated seconds to equilibrium
// from the straight line and after a perturbation, and the final F_c against
// the graph-search optimum on the same field.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <memory>

#include "base/version.hpp"
#include "fields/dense_level.hpp"
#include "fields/gdal/dem_io.hpp"
#include "rt/rope/planner.hpp"

namespace {

using namespace visvol;
using namespace visvol::rt;
using fields::DenseLevel;

struct World {
  std::vector<DenseLevel> levels;
  Vec3 from, to;
};

World& world() {
  static World* w = [] {
    auto* out = new World;
    auto full = fields::read_heightfield(std::string(VISVOL_TEST_DATA) + "/taunus_utm32n_90m_512.tif",
                                         {fields::NodataPolicy::fill});
    if (!full.ok()) {
      std::fprintf(stderr, "%s\n", full.status().message().c_str());
      std::exit(2);
    }
    fields::Heightfield hf;
    hf.nx = hf.ny = 256;
    hf.spacing_m = full->spacing_m;
    hf.origin_x = full->x_of(128);
    hf.origin_y = full->y_of(128);
    hf.height_m.resize(hf.size());
    for (int j = 0; j < 256; ++j)
      for (int i = 0; i < 256; ++i) hf.at(i, j) = full->at(128 + i, 128 + j);
    fields::FieldParams fp;
    fp.nz = 96;
    fp.range_posts = 32;
    fields::TffParams tp;
    auto levels = fields::build_dense_levels(hf, fp, 3, tp);
    if (!levels.ok()) std::exit(2);
    out->levels = std::move(*levels);
    const fields::FieldSampler<DenseLevel> s(out->levels[0]);
    out->from = {hf.x_of(20), hf.y_of(30), 0};
    out->to = {hf.x_of(235), hf.y_of(220), 0};
    out->from.z() = s.height(out->from.x(), out->from.y()) + 150;
    out->to.z() = s.height(out->to.x(), out->to.y()) + 150;
    return out;
  }();
  return *w;
}

void BM_RopeStep(benchmark::State& state) {
  World& w = world();
  const RopeModel model = state.range(0) == 0 ? RopeModel::spring : RopeModel::articulated;
  const int segments = static_cast<int>(state.range(1));
  ForceGains gains;
  FieldForces<DenseLevel> env(w.levels[0], gains);
  const double straight = (w.to - w.from).norm();
  const RopeParams p =
      scaled_rope_params(model, segments, 1.3 * straight / segments, 1.0, env.reference_acceleration());
  auto rope = make_rope(p);
  std::vector<Vec3> line = with_slack({w.from, w.to}, model == RopeModel::articulated ? 1.3 * straight : straight);
  RopeEnds ends;
  ends.start_m = w.from;
  ends.end_m = w.to;
  (*rope)->set_ends(ends);
  if (!(*rope)->reset(line.data(), static_cast<int>(line.size()), segments).ok()) state.SkipWithError("reset");
  (*rope)->set_ends(ends);
  for (auto _ : state) (*rope)->step(0.001, env);
  state.SetLabel(to_string(model));
}
BENCHMARK(BM_RopeStep)->ArgsProduct({{0, 1}, {32, 64, 128, 256, 512}})->Unit(benchmark::kMicrosecond);

void print_convergence() {
  World& w = world();
  std::vector<const DenseLevel*> levels;
  for (const DenseLevel& l : w.levels) levels.push_back(&l);
  std::printf("\nsettling on the Taunus window (256 x 256 posts, 90 m, range 32, 3 levels of detail):\n");
  std::printf(
      "model        start     F_c start  F_c final  graph F_c  sim s (finest)  sim s (all)  wall s  converged  "
      "requirements (fixed-wing, exact check)  answer\n");
  GlobalSearchParams gp;
  gp.objective = Objective::hide;
  gp.clearance_m = 30;
  auto g = global_search(w.levels[0], w.from, w.to, gp);
  FieldForces<DenseLevel> judge(w.levels[0], ForceGains{});
  const double graph_fc = g.ok() ? path_fc(g->points.data(), static_cast<int>(g->points.size()), judge, 256) : 0;
  for (RopeModel model : {RopeModel::articulated, RopeModel::spring}) {
    for (InitialPath init : {InitialPath::straight, InitialPath::global}) {
      PlanRequest r;
      r.from = w.from;
      r.to = w.to;
      r.model = model;
      r.init = init;
      r.segments = 128;
      auto res = plan(levels, r);
      if (!res.ok()) {
        std::printf("%s\n", res.status().message().c_str());
        continue;
      }
      std::printf("%-12s %-9s %9.4f  %9.4f  %9.4f  %14.1f  %11.1f  %6.2f  %-9s  %-38s  %s\n", to_string(model),
                  init == InitialPath::straight ? "straight" : "global", res->initial.fc, res->final_metrics.fc,
                  graph_fc, res->equilibrium_s, res->simulated_s, res->wall_s, res->converged ? "yes" : "no",
                  res->final_check.all_met ? "all met" : "NOT met", res->chosen.c_str());
      if (model == RopeModel::articulated && init == InitialPath::global) {
        // After a perturbation: start from the settled path lifted 200 m in its middle.
        std::vector<Vec3> bent = res->final_path;
        for (std::size_t i = 0; i < bent.size(); ++i)
          bent[i].z() += 200.0 * std::sin(M_PI * double(i) / double(bent.size() - 1));
        PlanRequest again = r;
        again.init = InitialPath::polyline;
        again.polyline = bent;
        again.slack = 0.0;
        std::vector<const DenseLevel*> finest{&w.levels[0]};
        auto res2 = plan(finest, again);
        if (res2.ok()) {
          std::printf("%-12s %-9s %9.4f  %9.4f  %9.4f  %14.1f  %11.1f  %6.2f  %-9s  %-38s  %s\n", "articulated",
                      "perturbed", res2->initial.fc, res2->final_metrics.fc, graph_fc, res2->equilibrium_s,
                      res2->simulated_s, res2->wall_s, res2->converged ? "yes" : "no",
                      res2->final_check.all_met ? "all met" : "NOT met", res2->chosen.c_str());
        }
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-ropebench")) return 0;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  print_convergence();
  return 0;
}
