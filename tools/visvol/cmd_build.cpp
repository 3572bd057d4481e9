// visvol build DEM: the visibility field and its levels of detail, with a summary.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "base/terminal_text.hpp"
#include "build_cli.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/pyramid.hpp"
#include "fields/sampler.hpp"
#include "io/json_text.hpp"
#include "storage/pack_build.hpp"

namespace visvol::cli {

namespace {

using fields::FieldParams;
using fields::Heightfield;
using fields::LodLevel;

struct LevelSummary {
  double min_f = 1, max_f = 0, mean_f = 0;  // over voxels at or above the terrain
};

LevelSummary summarise(const LodLevel& level) {
  LevelSummary s;
  const fields::VolumeGeometry& g = level.field.geometry;
  double sum = 0;
  std::size_t n = 0;
  for (int k = 0; k < g.nz; ++k) {
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        if (g.z_of(k) < level.terrain.at(i, j)) continue;
        const double v = level.field.at(i, j, k);
        s.min_f = std::min(s.min_f, v);
        s.max_f = std::max(s.max_f, v);
        sum += v;
        ++n;
      }
    }
  }
  s.mean_f = n ? sum / static_cast<double>(n) : 0.0;
  return s;
}

struct Sample {
  std::string where;
  double x, y, z, height_above_ground_m, f;
  Eigen::Vector3d gradient;
};

// F_p at a few telling places of level 0: over the highest post, the lowest
// post and the centre, at three heights above the ground.
std::vector<Sample> samples(const LodLevel& level) {
  const Heightfield& t = level.terrain;
  int hi = 0, lo = 0;
  for (std::size_t n = 1; n < t.size(); ++n) {
    if (t.height_m[n] > t.height_m[static_cast<std::size_t>(hi)]) hi = static_cast<int>(n);
    if (t.height_m[n] < t.height_m[static_cast<std::size_t>(lo)]) lo = static_cast<int>(n);
  }
  const fields::FieldSampler<fields::DenseLevelView> sampler(fields::DenseLevelView(level.terrain, level.field));
  std::vector<Sample> out;
  const struct {
    const char* name;
    int i, j;
  } places[] = {{"highest post", hi % t.nx, hi / t.nx},
                {"lowest post", lo % t.nx, lo / t.nx},
                {"grid centre", t.nx / 2, t.ny / 2}};
  for (const auto& p : places) {
    for (double above : {30.0, 150.0, 400.0}) {
      const double x = t.x_of(p.i), y = t.y_of(p.j), z = t.at(p.i, p.j) + above;
      out.push_back({p.name, x, y, z, above, sampler.visibility(x, y, z), sampler.gradient(x, y, z)});
    }
  }
  return out;
}

void print_text(const BuildOptions& o, const Heightfield& hf, const FieldParams& p, const std::vector<LodLevel>& levels,
                const std::vector<fields::BuildStats>& stats, double wall_s) {
  const fields::HeightRange hr = fields::height_range(hf);
  const fields::VolumeGeometry& g = levels[0].field.geometry;
  std::printf("DEM        %s\n", terminal_safe(o.dem).c_str());
  std::printf("           %d x %d posts, %.2f m spacing, %s, heights %.1f..%.1f m\n", hf.nx, hf.ny, hf.spacing_m,
              terminal_safe(fields::crs_name(hf.crs_wkt), 200).c_str(), hr.min_m, hr.max_m);
  std::printf("field      %d levels from %.1f m every %.2f m (top %.1f m), eye %.2f m,\n", g.nz, g.z0_m, g.dz_m,
              g.top_m(), p.eye_height_m);
  std::printf("           range %s %d posts, curvature %.5f, %d exact rings\n", fields::to_string(p.range_shape),
              p.range_posts, p.curvature_coeff, p.exact_rings);
  std::printf(
      "\nlevel  grid              spacing  range      time    hull cells  Mcells/s/core  F_p min..max (mean)\n");
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const fields::VolumeGeometry& lg = levels[l].field.geometry;
    const LevelSummary s = summarise(levels[l]);
    char grid[64];
    std::snprintf(grid, sizeof grid, "%dx%dx%d", lg.nx, lg.ny, lg.nz);
    std::printf("%5zu  %-16s %6.0f m  %7.0f m  %6.2f s  %10.3g  %13.1f  %.4f..%.4f (%.4f)\n", l, grid, lg.spacing_m,
                p.range_posts * lg.spacing_m, stats[l].wall_s, static_cast<double>(stats[l].hull_cells),
                stats[l].cells_per_s_per_core() / 1e6, s.min_f, s.max_f, s.mean_f);
  }
  std::printf("\nsamples of level 0 (world x, y, z in the DEM's CRS, metres):\n");
  for (const Sample& s : samples(levels[0])) {
    std::printf("  %-13s %+6.0f m  (%.1f, %.1f, %.1f)  F_p %.4f  grad (%.2e, %.2e, %.2e) /m\n", s.where.c_str(),
                s.height_above_ground_m, s.x, s.y, s.z, s.f, s.gradient.x(), s.gradient.y(), s.gradient.z());
  }
  std::printf("\ntotal %.2f s on %d threads\n", wall_s, stats[0].threads);
}

// What every build summary says of its terrain and field parameters.
nlohmann::json build_inputs_json(const BuildOptions& o, const Heightfield& hf, const FieldParams& p) {
  const fields::HeightRange hr = fields::height_range(hf);
  nlohmann::json j;
  j["dem"] = o.dem;
  j["nx"] = hf.nx;
  j["ny"] = hf.ny;
  j["cell_size_m"] = hf.spacing_m;
  j["origin_x"] = hf.origin_x;
  j["origin_y"] = hf.origin_y;
  j["crs"] = fields::crs_name(hf.crs_wkt);
  j["height_min_m"] = hr.min_m;
  j["height_max_m"] = hr.max_m;
  j["nz"] = p.nz;
  j["eye_height_m"] = p.eye_height_m;
  j["range_shape"] = fields::to_string(p.range_shape);
  j["range_posts"] = p.range_posts;
  j["curvature_coeff"] = p.curvature_coeff;
  j["exact_rings"] = p.exact_rings;
  return j;
}

std::string summary_json(const BuildOptions& o, const Heightfield& hf, const FieldParams& p,
                         const std::vector<LodLevel>& levels, const std::vector<fields::BuildStats>& stats,
                         double wall_s) {
  using nlohmann::json;
  json j = build_inputs_json(o, hf, p);
  const fields::VolumeGeometry& g = levels[0].field.geometry;
  j["nz"] = g.nz;
  j["z0_m"] = g.z0_m;
  j["dz_m"] = g.dz_m;
  j["threads"] = stats[0].threads;
  j["wall_s"] = wall_s;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const fields::VolumeGeometry& lg = levels[l].field.geometry;
    const LevelSummary s = summarise(levels[l]);
    j["levels_of_detail"].push_back({{"nx", lg.nx},
                                     {"ny", lg.ny},
                                     {"spacing_m", lg.spacing_m},
                                     {"range_m", p.range_posts * lg.spacing_m},
                                     {"wall_s", stats[l].wall_s},
                                     {"hull_cells", stats[l].hull_cells},
                                     {"cells_per_s_per_core", stats[l].cells_per_s_per_core()},
                                     {"f_min", s.min_f},
                                     {"f_max", s.max_f},
                                     {"f_mean", s.mean_f}});
  }
  for (const Sample& s : samples(levels[0])) {
    j["samples"].push_back({{"where", s.where},
                            {"x", s.x},
                            {"y", s.y},
                            {"z", s.z},
                            {"above_ground_m", s.height_above_ground_m},
                            {"f", s.f},
                            {"gradient_per_m", {s.gradient.x(), s.gradient.y(), s.gradient.z()}}});
  }
  return json_text(j, 2) + "\n";
}

// The summary of a pack build as JSON: what print_pack_summary says, and the pack.
std::string pack_summary_json(const BuildOptions& o, const PreparedBuild& b, const storage::PackBuildReport& report) {
  const Heightfield& hf = b.terrain;
  const FieldParams& p = b.params;
  nlohmann::json j = build_inputs_json(o, hf, p);
  for (std::size_t l = 0; l < report.levels.size(); ++l) {
    const double spacing = hf.spacing_m * static_cast<double>(1 << l);
    j["levels_of_detail"].push_back({{"nx", hf.nx >> l},
                                     {"ny", hf.ny >> l},
                                     {"spacing_m", spacing},
                                     {"range_m", p.range_posts * spacing},
                                     {"wall_s", report.levels[l].wall_s},
                                     {"hull_cells", report.levels[l].hull_cells},
                                     {"cells_per_s_per_core", report.levels[l].cells_per_s_per_core()}});
  }
  j["terrain_force_field"] = {{"wall_s", report.tff_s}, {"band_offset_m", o.tff_offset_m}, {"levels", o.tff_levels}};
  j["planning_bounds"] = storage::planning_json(report.planning);
  j["pack"] = {{"path", o.out}, {"bytes", report.file_bytes}};
  j["wall_s"] = report.wall_s;
  return json_text(j, 2) + "\n";
}

// Do two output names name one file (the pack need not exist yet)? By their
// folders as resolved and their last names.
bool names_one_file(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  const std::filesystem::path pa = std::filesystem::weakly_canonical(std::filesystem::absolute(a, ea), ea);
  const std::filesystem::path pb = std::filesystem::weakly_canonical(std::filesystem::absolute(b, eb), eb);
  return !ea && !eb && pa == pb;
}

int run_pack_build(const BuildOptions& o, const PreparedBuild& b) {
  storage::PackBuildReport report;
  Progress progress("building " + o.out);
  const Status st = storage::build_pack(
      b.terrain, pack_build_params(o, b), build_source_json(o, b), o.out, [&](double f) { progress.update(f); },
      &report);
  if (!st.ok()) return fail("build", st);
  progress.finish();
  // --json and --json-file as for a build in memory (they were ignored with -o)
  if (o.json) {
    std::printf("%s", pack_summary_json(o, b, report).c_str());
  } else {
    print_pack_summary(o, b, report);
  }
  if (!o.json_file.empty()) {
    const Status written = write_text_file(o.json_file, pack_summary_json(o, b, report));
    if (!written.ok()) return fail("build", written.with_context("--json-file"));
  }
  return kExitOk;
}

int run_build(const BuildOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  // a bad summary file costs nothing: refused before the build, by name
  if (!o.json_file.empty()) {
    if (Status s = check_output_path(o.json_file); !s.ok()) return fail("build", s.with_context("--json-file"));
    // the summary written over the pack just built
    if (!o.out.empty() && names_one_file(o.json_file, o.out)) {
      return fail("build", invalid_argument("--json-file " + o.json_file + " is the pack's -o: name another file"));
    }
  }
  Result<PreparedBuild> prepared = prepare_build(o);
  if (!prepared.ok()) return fail("build", prepared.status());
  for (const std::string& w : prepared->warnings) {
    std::fprintf(stderr, "visvol build: warning: %s\n", terminal_safe(w).c_str());
  }
  if (!o.out.empty()) return run_pack_build(o, *prepared);
  const Heightfield& hf = prepared->terrain;
  const FieldParams& params = prepared->params;

  std::vector<fields::BuildStats> stats;
  Result<std::vector<LodLevel>> levels = [&] {
    Progress progress("building F_p");
    auto r = fields::build_pyramid_dense(
        hf, params, o.lod, [&](double f) { progress.update(f); }, &stats);
    if (r.ok()) progress.finish();
    return r;
  }();
  if (!levels.ok()) return fail("build", levels.status());
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    std::printf("%s", summary_json(o, hf, params, *levels, stats, wall_s).c_str());
  } else {
    print_text(o, hf, params, *levels, stats, wall_s);
  }
  if (!o.json_file.empty()) {
    const Status st = write_text_file(o.json_file, summary_json(o, hf, params, *levels, stats, wall_s));
    if (!st.ok()) return fail("build", st.with_context("--json-file"));
  }
  return kExitOk;
}

}  // namespace

Runner add_build_command(CLI::App& app) {
  auto o = std::make_shared<BuildOptions>();
  CLI::App* c =
      app.add_subcommand("build",
                         "Build the visibility field F_p of a DEM, its levels of detail and the terrain force field "
                         "into a field pack (-o), or in memory with a summary only");
  add_build_options(c, *o);
  c->add_option("-o,--output", o->out, "Field pack to write (written whole or not at all)");
  c->add_flag("--json", o->json, "Print the summary as one JSON object");
  c->add_option("--json-file", o->json_file, "Also write the JSON summary to this file");
  return [o] { return run_build(*o); };
}

}  // namespace visvol::cli
