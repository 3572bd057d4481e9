#include "build_cli.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/terminal_text.hpp"
#include "cli.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/terrain_force.hpp"
#include "io/json_text.hpp"
#include "storage/planning_bounds.hpp"
#include "wgs84.hpp"

namespace visvol::cli {

using fields::FieldParams;
using fields::Heightfield;

void add_build_options(CLI::App* c, BuildOptions& o) {
  c->add_option("DEM", o.dem, "Terrain: GeoTIFF, SRTM .hgt, USGS .dem, ESRI or GRASS ASCII grid, DTED")->required();
  c->add_option("--levels", o.levels, "Voxel levels in height (2..255)")->capture_default_str();
  c->add_option("--ceiling", o.ceiling_m, "Height of the top level above the highest post, m")->capture_default_str();
  c->add_option("--eye-height", o.eye_m, "Observer eye above its post, m")->capture_default_str();
  c->add_option("--range", o.range_posts, "Range in posts: cube half-side or sphere radius")->capture_default_str();
  c->add_option("--range-shape", o.range_shape, "none, cube (the paper's) or sphere")->capture_default_str();
  c->add_option("--curvature", o.curvature, "Earth curvature and refraction coefficient, 0 off (0.85714 is usual)")
      ->capture_default_str();
  c->add_option("--weights", o.weights, "Observer likelihood raster in [0, 1] on the DEM's grid");
  c->add_option("--lod", o.lod, "Levels of detail (each halves the grid)")->capture_default_str();
  c->add_option("--threads", o.threads, "Worker threads, 0 for all cores")->capture_default_str();
  c->add_option("--exact-rings", o.exact_rings, "Rings around each observer evaluated exactly")->capture_default_str();
  c->add_option("--encoding", o.encoding, "F_p in the pack: uint16 (quantised) or float32")
      ->check(CLI::IsMember({"uint16", "float32"}))
      ->capture_default_str();
  c->add_option("--tff-offset", o.tff_offset_m, "Terrain force field band: this far below and above the terrain, m")
      ->capture_default_str();
  c->add_option("--tff-levels", o.tff_levels, "Terrain force field samples per column")->capture_default_str();
  add_import_options(c, o.import);
  c->add_option("--area", o.area,
                "Plan over the box XMIN YMIN XMAX YMAX (output CRS, m): import it with the planning "
                "margin around it, so that it lies inside the pack's planning bounds (not with --crop)")
      ->expected(4);
  c->add_option("--planning-margin", o.planning_margin_m,
                "Planning bounds: this far inside the DEM's posts on every side, m (default: the range "
                "in metres; for --range-shape none, 1/8 of the DEM's smaller side)");
  c->add_option("--max-memory", o.max_memory_mib,
                "Refuse builds needing more memory, MiB (at most 16777216, 16 TiB): the grid at 48 bytes a post, "
                "checked before the import, then the field's working set")
      ->capture_default_str();
}

Result<FieldParams> make_params(const BuildOptions& o, const Heightfield& hf, const std::vector<float>* weights) {
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
  // the builder's share: what the build holds a post is not the builder's
  const double held_mib =
      static_cast<double>(hf.nx) * static_cast<double>(hf.ny) * kHeldBytesPerPost / (1024.0 * 1024.0);
  p.max_memory_mib = o.max_memory_mib - held_mib;
  if (!(p.max_memory_mib >= 1)) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "--max-memory %g MiB: the terrain's %d x %d posts hold %.0f MiB before the "
                  "field's working memory",
                  o.max_memory_mib, hf.nx, hf.ny, held_mib);
    return Status(Errc::resource, text);
  }
  if (weights) {
    p.weights = *weights;
  } else if (!o.weights.empty()) {
    Result<std::vector<float>> w = fields::read_raster_like(o.weights, hf);
    if (!w.ok()) return w.status();
    p.weights = std::move(*w);
  }
  VISVOL_RETURN_IF_ERROR(fields::validate(p, hf));
  return p;
}

namespace {

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

// The terrain force field's band as the options give it, checked before
// anything is imported or built (with or without a pack to write).
Status check_tff_options(const BuildOptions& o) {
  if (!(o.tff_offset_m >= fields::kMinBandOffsetM && o.tff_offset_m <= fields::kMaxBandOffsetM)) {
    return invalid_argument("--tff-offset: " + number_text(o.tff_offset_m) + " m is not in " +
                            number_text(fields::kMinBandOffsetM) + ".." + number_text(fields::kMaxBandOffsetM) + " m");
  }
  if (o.tff_levels < 2 || o.tff_levels > fields::kMaxBandLevels) {
    return invalid_argument("--tff-levels: " + std::to_string(o.tff_levels) + " is not in 2.." +
                            std::to_string(fields::kMaxBandLevels));
  }
  // posts resampled this fine: refused before the import (the DEM's own: after it; a spacing out of range: by it)
  if (o.import.spacing_m >= fields::kMinPostSpacingM && o.import.spacing_m <= fields::kMaxPostSpacingM) {
    fields::TffParams t;
    t.band_offset_m = o.tff_offset_m;
    t.band_levels = o.tff_levels;
    return fields::validate(t, o.import.spacing_m);
  }
  return Status::ok_status();
}

Result<BuildInput> build_input(const BuildOptions& o) {
  VISVOL_RETURN_IF_ERROR(check_planning_margin(o.planning_margin_m));
  VISVOL_RETURN_IF_ERROR(check_tff_options(o));
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

// A DEM whose CRS plans convert to WGS84 must lie where that CRS places
// points on Earth (a UTM grid at northing 9e7 m built, and every plan's WGS84
// step on it then failed). A DEM without a CRS, or with one plans cannot
// convert (not projected in metres, unknown to PROJ: `warnings` says so),
// gets plans in its own coordinates (the CSV) only.
Status check_place_on_earth(const std::string& dem, const Heightfield& hf, std::vector<std::string>& warnings) {
  if (hf.crs_wkt.empty()) return Status::ok_status();
  const double east = hf.x_of(hf.nx - 1), south = hf.y_of(hf.ny - 1);
  const std::vector<Vec3> corners = {
      {hf.origin_x, hf.origin_y, 0}, {east, hf.origin_y, 0}, {hf.origin_x, south, 0}, {east, south, 0}};
  const char* names[] = {"north-west", "north-east", "south-west", "south-east"};
  const std::string crs = fields::crs_name(hf.crs_wkt);
  const std::string why = "; plans give WGS84 positions through it, so check the DEM's georeferencing";
  // a CRS plans do not convert (a site grid's, one PROJ names no projection
  // for): said; one that does not parse, or that PROJ cannot use here: refused
  const std::optional<bool> metres = projected_in_metres(hf.crs_wkt);
  if (!metres) return invalid_argument(dem + ": its CRS does not parse");
  if (!*metres) {
    warnings.push_back(dem + ": its CRS (" + crs +
                       ") is not a projected CRS in metres: plans on this pack give no WGS84 positions (their CSV, in "
                       "the pack's coordinates, only)");
    return Status::ok_status();
  }
  // one transformation for the four corners; where that fails, the CRS or
  // the corner that does
  if (to_wgs84(corners, hf.crs_wkt).ok()) return Status::ok_status();
  if (const auto usable = to_wgs84({}, hf.crs_wkt); !usable.ok()) {
    return invalid_argument(dem + ": " + usable.status().message() + why);
  }
  for (std::size_t n = 0; n < corners.size(); ++n) {
    if (to_wgs84({corners[n]}, hf.crs_wkt).ok()) continue;
    char where[96];
    std::snprintf(where, sizeof where, "%s post (%.2f, %.2f)", names[n], corners[n].x(), corners[n].y());
    return invalid_argument(dem + ": its " + where + " is no place on Earth in its CRS (" + crs + ")" + why);
  }
  return Status::ok_status();
}

}  // namespace

std::string build_source_json(const BuildOptions& o, const PreparedBuild& b) {
  nlohmann::json j = nlohmann::json::parse(source_json(o.dem, b.input.import, b.imported));
  if (!o.area.empty()) j["import"]["area"] = o.area;
  return json_text(j);
}

Result<PreparedBuild> prepare_build(const BuildOptions& o) {
  const std::vector<std::pair<std::string, std::string>> inputs = {{"DEM", o.dem}, {"--weights", o.weights}};
  VISVOL_RETURN_IF_ERROR(output_is_no_input(o.out, "-o", inputs));
  VISVOL_RETURN_IF_ERROR(output_is_no_input(o.json_file, "--json-file", inputs));
  PreparedBuild b;
  Result<BuildInput> in = build_input(o);
  if (!in.ok()) return in.status();
  b.input = std::move(*in);
  // the import and the build's arrays a post, within --max-memory before a
  // byte is read (1 m posts of SF North took 9 GB under the default 8 GiB)
  const double posts = o.max_memory_mib * 1024.0 * 1024.0 / kBuildBytesPerPost;
  b.input.import.max_posts = posts >= 1 ? static_cast<std::size_t>(std::min(posts, 1e18)) : 1;
  char reason[96];
  std::snprintf(reason, sizeof reason, "--max-memory %g MiB at %d bytes a post", o.max_memory_mib, kBuildBytesPerPost);
  b.input.import.max_posts_reason = reason;
  Result<Heightfield> hf = import(o.dem, b.input.import, &b.imported);
  if (!hf.ok()) return hf.status();
  b.terrain = std::move(*hf);
  VISVOL_RETURN_IF_ERROR(check_place_on_earth(o.dem, b.terrain, b.warnings));
  Result<FieldParams> params = make_params(o, b.terrain);
  if (!params.ok()) return params.status();
  b.params = std::move(*params);
  VISVOL_RETURN_IF_ERROR(check_area_inside(o, b.input, b.terrain, b.params));
  return b;
}

storage::PackBuildParams pack_build_params(const BuildOptions& o, const PreparedBuild& b) {
  storage::PackBuildParams pp;
  pp.field = b.params;
  pp.lod_levels = o.lod;
  pp.encoding = o.encoding == "float32" ? storage::VisibilityEncoding::float32 : storage::VisibilityEncoding::uint16;
  pp.tff.band_offset_m = o.tff_offset_m;
  pp.tff.band_levels = o.tff_levels;
  pp.crs_name = fields::crs_name(b.terrain.crs_wkt);
  pp.planning_margin_m = b.input.planning_margin_m;
  return pp;
}

void print_pack_summary(const BuildOptions& o, const PreparedBuild& b, const storage::PackBuildReport& report) {
  const Heightfield& hf = b.terrain;
  const FieldParams& p = b.params;
  const fields::ImportReport& imported = b.imported;
  const fields::HeightRange hr = fields::height_range(hf);
  std::printf("DEM        %s (%s, %d x %d)\n", terminal_safe(o.dem).c_str(), imported.source.driver.c_str(),
              imported.source.nx, imported.source.ny);
  if (!imported.steps.empty()) std::printf("import     %s\n", terminal_safe(imported.steps).c_str());
  std::printf("terrain    %d x %d posts, %.2f m spacing, %s, heights %.1f..%.1f m\n", hf.nx, hf.ny, hf.spacing_m,
              terminal_safe(fields::crs_name(hf.crs_wkt), 200).c_str(), hr.min_m, hr.max_m);
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

}  // namespace visvol::cli
