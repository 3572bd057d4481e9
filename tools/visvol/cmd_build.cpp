// visvol build DEM: the visibility field and its levels of detail, with a summary.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "cli.hpp"
#include "commands.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/pyramid.hpp"
#include "fields/sampler.hpp"
#include "import_cli.hpp"
#include "io/json_text.hpp"
#include "storage/pack_build.hpp"
#include "storage/planning_bounds.hpp"

namespace visvol::cli {

namespace {

using fields::FieldParams;
using fields::Heightfield;
using fields::LodLevel;

struct BuildOptions {
  std::string dem;
  std::string out;
  ImportCli import;
  std::string encoding = "uint16";
  double tff_offset_m = 100.0;
  int tff_levels = 24;
  int levels = 128;
  double ceiling_m = 300.0;
  double eye_m = 2.0;
  std::string range_shape = "cube";
  int range_posts = 64;
  double curvature = 0.0;
  std::string weights;
  int lod = 3;
  int threads = 0;
  int exact_rings = 16;
  double max_memory_mib = 8192.0;
  std::vector<double> area;  // xmin ymin xmax ymax, output CRS metres
  std::optional<double> planning_margin_m;
  bool json = false;
  std::string json_file;
};

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

Result<FieldParams> make_params(const BuildOptions& o, const Heightfield& hf) {
  FieldParams p;
  p.nz = o.levels;
  p.ceiling_m = o.ceiling_m;
  p.eye_height_m = o.eye_m;
  Result<fields::RangeShape> shape = fields::parse_range_shape(o.range_shape);
  if (!shape.ok()) return shape.status();
  p.range_shape = *shape;
  p.range_posts = o.range_posts;
  p.curvature_coeff = o.curvature;
  p.threads = o.threads;
  p.exact_rings = o.exact_rings;
  p.max_memory_mib = o.max_memory_mib;
  if (!o.weights.empty()) {
    Result<std::vector<float>> w = fields::read_raster_like(o.weights, hf);
    if (!w.ok()) return w.status();
    p.weights = std::move(*w);
  }
  VISVOL_RETURN_IF_ERROR(fields::validate(p, hf));
  return p;
}

// What the build imports and records: the import options (--crop as given,
// or the crop --area needs) and the planning margin to record, if not the rule's.
struct BuildInput {
  ImportCli import;
  std::optional<double> planning_margin_m;
};

std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

Status check_planning_margin(const std::optional<double>& margin_m) {
  if (!margin_m || (std::isfinite(*margin_m) && *margin_m >= 0)) return Status::ok_status();
  return invalid_argument("--planning-margin: " + number_text(*margin_m) + " m is not a finite number >= 0");
}

// The margin an --area build crops for: --planning-margin, or the range in
// metres, or for --range-shape none a sixth of the area's smaller side (an
// eighth of the DEM that results, as the rule wants).
double area_margin_m(const BuildOptions& o, fields::RangeShape shape, const fields::BoundingBox& area,
                     double spacing_m) {
  if (o.planning_margin_m) return *o.planning_margin_m;
  if (shape != fields::RangeShape::none) return std::max(0, o.range_posts) * spacing_m;
  const double smaller_side_m = std::min(area.xmax - area.xmin, area.ymax - area.ymin);
  return smaller_side_m / (storage::kUnrangedMarginDivisor - 2.0);
}

Result<BuildInput> build_input(const BuildOptions& o) {
  VISVOL_RETURN_IF_ERROR(check_planning_margin(o.planning_margin_m));
  BuildInput in{o.import, o.planning_margin_m};
  if (o.area.empty()) return in;
  if (!o.import.crop.empty()) {
    return invalid_argument("--area and --crop: give one (--area crops to the area and its planning margin)");
  }
  const fields::BoundingBox area{o.area[0], o.area[1], o.area[2], o.area[3]};
  Result<fields::RangeShape> shape = fields::parse_range_shape(o.range_shape);
  if (!shape.ok()) return shape.status();
  Result<fields::ImportGrid> grid = fields::import_grid(o.dem, import_options(o.import));
  if (!grid.ok()) return grid.status();
  const double margin_m = area_margin_m(o, *shape, area, grid->spacing_m);
  Result<fields::BoundingBox> crop = fields::crop_for_area(*grid, area, margin_m, "--area");
  if (!crop.ok()) return crop.status();
  in.import.crop = {crop->xmin, crop->ymin, crop->xmax, crop->ymax};
  // A warp to a crop picks its own spacing unless told: keep the one the margin was measured in.
  if (!grid->aligned) in.import.spacing_m = grid->spacing_m;
  if (*shape == fields::RangeShape::none) in.planning_margin_m = margin_m;
  return in;
}

// The planning bounds of an --area build hold the area: the crop makes them
// so, and this says so loudly, before building, if GDAL ever laid the grid
// otherwise.
Status check_area_inside(const BuildOptions& o, const BuildInput& in, const Heightfield& hf,
                         const FieldParams& params) {
  if (o.area.empty()) return Status::ok_status();
  const fields::VolumeGeometry finest = fields::volume_geometry(hf, params);
  const fields::Bounds2D b =
      storage::planning_bounds_rule(finest, params.range_shape, params.range_posts, in.planning_margin_m).box;
  const double rounding_m = 1e-6;
  if (b.xmin_m <= o.area[0] + rounding_m && b.ymin_m <= o.area[1] + rounding_m && b.xmax_m >= o.area[2] - rounding_m &&
      b.ymax_m >= o.area[3] - rounding_m) {
    return Status::ok_status();
  }
  return Status(Errc::state, "--area: the planning bounds " + storage::describe(b) +
                                 " of the imported grid do not hold the area; this is a bug");
}

// The source description, with the area the crop came from.
std::string build_source_json(const BuildOptions& o, const BuildInput& in, const fields::ImportReport& imported) {
  nlohmann::json j = nlohmann::json::parse(source_json(o.dem, in.import, imported));
  if (!o.area.empty()) j["import"]["area"] = o.area;
  return json_text(j);
}

void print_text(const BuildOptions& o, const Heightfield& hf, const FieldParams& p, const std::vector<LodLevel>& levels,
                const std::vector<fields::BuildStats>& stats, double wall_s) {
  const fields::HeightRange hr = fields::height_range(hf);
  const fields::VolumeGeometry& g = levels[0].field.geometry;
  std::printf("DEM        %s\n", o.dem.c_str());
  std::printf("           %d x %d posts, %.2f m spacing, %s, heights %.1f..%.1f m\n", hf.nx, hf.ny, hf.spacing_m,
              fields::crs_name(hf.crs_wkt).c_str(), hr.min_m, hr.max_m);
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

std::string summary_json(const BuildOptions& o, const Heightfield& hf, const FieldParams& p,
                         const std::vector<LodLevel>& levels, const std::vector<fields::BuildStats>& stats,
                         double wall_s) {
  using nlohmann::json;
  const fields::HeightRange hr = fields::height_range(hf);
  json j;
  j["dem"] = o.dem;
  j["nx"] = hf.nx;
  j["ny"] = hf.ny;
  j["cell_size_m"] = hf.spacing_m;
  j["origin_x"] = hf.origin_x;
  j["origin_y"] = hf.origin_y;
  j["crs"] = fields::crs_name(hf.crs_wkt);
  j["height_min_m"] = hr.min_m;
  j["height_max_m"] = hr.max_m;
  const fields::VolumeGeometry& g = levels[0].field.geometry;
  j["nz"] = g.nz;
  j["z0_m"] = g.z0_m;
  j["dz_m"] = g.dz_m;
  j["eye_height_m"] = p.eye_height_m;
  j["range_shape"] = fields::to_string(p.range_shape);
  j["range_posts"] = p.range_posts;
  j["curvature_coeff"] = p.curvature_coeff;
  j["exact_rings"] = p.exact_rings;
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

void print_pack_summary(const BuildOptions& o, const Heightfield& hf, const FieldParams& p,
                        const fields::ImportReport& imported, const storage::PackBuildReport& report) {
  const fields::HeightRange hr = fields::height_range(hf);
  std::printf("DEM        %s (%s, %d x %d)\n", o.dem.c_str(), imported.source.driver.c_str(), imported.source.nx,
              imported.source.ny);
  if (!imported.steps.empty()) std::printf("import     %s\n", imported.steps.c_str());
  std::printf("terrain    %d x %d posts, %.2f m spacing, %s, heights %.1f..%.1f m\n", hf.nx, hf.ny, hf.spacing_m,
              fields::crs_name(hf.crs_wkt).c_str(), hr.min_m, hr.max_m);
  std::printf("field      %d levels, range %s %d posts, eye %.2f m, curvature %.5f, %d exact rings\n", p.nz,
              fields::to_string(p.range_shape), p.range_posts, p.eye_height_m, p.curvature_coeff, p.exact_rings);
  std::printf("\nlevel  grid         spacing  range      F_p time  Mcells/s/core\n");
  for (std::size_t l = 0; l < report.levels.size(); ++l) {
    const double spacing = hf.spacing_m * static_cast<double>(1 << l);
    char grid[32];
    std::snprintf(grid, sizeof grid, "%dx%d", hf.nx >> l, hf.ny >> l);
    std::printf("%5zu  %-11s %6.0f m  %7.0f m  %6.2f s  %13.1f\n", l, grid, spacing, p.range_posts * spacing,
                report.levels[l].wall_s, report.levels[l].cells_per_s_per_core() / 1e6);
  }
  std::printf("\nterrain force field %.2f s (band +-%.0f m, %d levels)\n", report.tff_s, o.tff_offset_m, o.tff_levels);
  std::printf("planning   %s\n", storage::describe(report.planning).c_str());
  std::printf("pack       %s, %.1f MiB, written in %.2f s\n", o.out.c_str(),
              static_cast<double>(report.file_bytes) / (1024.0 * 1024.0), report.wall_s);
}

int run_pack_build(const BuildOptions& o, const BuildInput& in, const Heightfield& hf, const FieldParams& params,
                   const fields::ImportReport& imported) {
  storage::PackBuildParams pp;
  pp.field = params;
  pp.lod_levels = o.lod;
  pp.encoding = o.encoding == "float32" ? storage::VisibilityEncoding::float32 : storage::VisibilityEncoding::uint16;
  pp.tff.band_offset_m = o.tff_offset_m;
  pp.tff.band_levels = o.tff_levels;
  pp.crs_name = fields::crs_name(hf.crs_wkt);
  pp.planning_margin_m = in.planning_margin_m;
  storage::PackBuildReport report;
  Progress progress("building " + o.out);
  const Status st = storage::build_pack(
      hf, pp, build_source_json(o, in, imported), o.out, [&](double f) { progress.update(f); }, &report);
  if (!st.ok()) return fail("build", st);
  progress.finish();
  print_pack_summary(o, hf, params, imported, report);
  return kExitOk;
}

int run_build(const BuildOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Result<BuildInput> in = build_input(o);
  if (!in.ok()) return fail("build", in.status());
  fields::ImportReport imported;
  Result<Heightfield> hf = import(o.dem, in->import, &imported);
  if (!hf.ok()) return fail("build", hf.status());
  Result<FieldParams> params = make_params(o, *hf);
  if (!params.ok()) return fail("build", params.status());
  const Status inside = check_area_inside(o, *in, *hf, *params);
  if (!inside.ok()) return fail("build", inside);
  if (!o.out.empty()) return run_pack_build(o, *in, *hf, *params, imported);

  std::vector<fields::BuildStats> stats;
  Result<std::vector<LodLevel>> levels = [&] {
    Progress progress("building F_p");
    auto r = fields::build_pyramid_dense(
        *hf, *params, o.lod, [&](double f) { progress.update(f); }, &stats);
    if (r.ok()) progress.finish();
    return r;
  }();
  if (!levels.ok()) return fail("build", levels.status());
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    std::printf("%s", summary_json(o, *hf, *params, *levels, stats, wall_s).c_str());
  } else {
    print_text(o, *hf, *params, *levels, stats, wall_s);
  }
  if (!o.json_file.empty()) {
    const Status st = write_text_file(o.json_file, summary_json(o, *hf, *params, *levels, stats, wall_s));
    if (!st.ok()) return fail("build", st);
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
  c->add_option("DEM", o->dem, "Terrain: GeoTIFF, SRTM .hgt, USGS .dem, ESRI or GRASS ASCII grid, DTED")->required();
  c->add_option("-o,--output", o->out, "Field pack to write (written whole or not at all)");
  c->add_option("--levels", o->levels, "Voxel levels in height (2..255)")->capture_default_str();
  c->add_option("--ceiling", o->ceiling_m, "Height of the top level above the highest post, m")->capture_default_str();
  c->add_option("--eye-height", o->eye_m, "Observer eye above its post, m")->capture_default_str();
  c->add_option("--range", o->range_posts, "Range in posts: cube half-side or sphere radius")->capture_default_str();
  c->add_option("--range-shape", o->range_shape, "none, cube (the paper's) or sphere")->capture_default_str();
  c->add_option("--curvature", o->curvature, "Earth curvature and refraction coefficient, 0 off (0.85714 is usual)")
      ->capture_default_str();
  c->add_option("--weights", o->weights, "Observer likelihood raster in [0, 1] on the DEM's grid");
  c->add_option("--lod", o->lod, "Levels of detail (each halves the grid)")->capture_default_str();
  c->add_option("--threads", o->threads, "Worker threads, 0 for all cores")->capture_default_str();
  c->add_option("--exact-rings", o->exact_rings, "Rings around each observer evaluated exactly")->capture_default_str();
  c->add_option("--encoding", o->encoding, "F_p in the pack: uint16 (quantised) or float32")
      ->check(CLI::IsMember({"uint16", "float32"}))
      ->capture_default_str();
  c->add_option("--tff-offset", o->tff_offset_m, "Terrain force field band: this far below and above the terrain, m")
      ->capture_default_str();
  c->add_option("--tff-levels", o->tff_levels, "Terrain force field samples per column")->capture_default_str();
  add_import_options(c, o->import);
  c->add_option("--area", o->area,
                "Plan over the box XMIN YMIN XMAX YMAX (output CRS, m): import it with the planning "
                "margin around it, so that it lies inside the pack's planning bounds (not with --crop)")
      ->expected(4);
  c->add_option("--planning-margin", o->planning_margin_m,
                "Planning bounds: this far inside the DEM's posts on every side, m (default: the range "
                "in metres; for --range-shape none, 1/8 of the DEM's smaller side)");
  c->add_option("--max-memory", o->max_memory_mib,
                "Refuse builds needing more working memory, MiB (at most 16777216, 16 TiB)")
      ->capture_default_str();
  c->add_flag("--json", o->json, "Print the summary as one JSON object");
  c->add_option("--json-file", o->json_file, "Also write the JSON summary to this file");
  return [o] { return run_build(*o); };
}

}  // namespace visvol::cli
