// visvol render PACK [--path FILE] [--size WxH] [--view V] [--transfer FILE] -o OUT.png:
// a thumbnail of the terrain, its visibility field and a path (drivers/render).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "cli.hpp"
#include "commands.hpp"
#include "drivers/render/png_encoder.hpp"
#include "drivers/render/renderer.hpp"
#include "fields/sampler.hpp"
#include "io/atomic_file.hpp"
#include "pack_planner.hpp"  // the planner and sampler for packs: compiled in visvol_pack_planner
#include "path_io.hpp"
#include "rt/rope/path_check.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::cli {

namespace {

using render::PathPoint;
using storage::PackLevel;

// A path vertex may lie this fraction of the pack's larger side outside it.
constexpr double kPathOutsideFraction = 0.05;
// `visvol plan` makes at most 100000 segments.
constexpr std::size_t kMaxRenderPathPoints = 100001;

struct RenderOptions {
  std::string pack, path, size = "512x384", view = "oblique", transfer, out;
  std::vector<std::vector<double>> hidden_from, visible_to;
  double height_above_ground_m = 0;
  bool height_given = false;  // --height-above-ground given
  double exaggeration = 0;
  double fp_max = 0;
  int compression = 6;
};

int fail_render(const Status& s) {
  // a GL or libpng failure is the machine's, not the input's
  if (s.code() == Errc::unsupported || s.code() == Errc::resource || s.code() == Errc::state) {
    std::fprintf(stderr, "visvol render: %s\n", s.message().c_str());
    return kExitFailure;
  }
  return fail("render", s);
}

Status parse_size(const std::string& text, int& width, int& height) {
  const std::size_t x = text.find('x');
  const auto number = [](const std::string& s, int& out) {
    if (s.empty() || s.size() > 5 || s.find_first_not_of("0123456789") != std::string::npos) return false;
    out = std::atoi(s.c_str());
    return true;
  };
  if (x == std::string::npos || !number(text.substr(0, x), width) || !number(text.substr(x + 1), height)) {
    return invalid_argument("--size '" + text + "' is not WIDTHxHEIGHT (for example 512x384)");
  }
  if (width < render::kMinSidePx || height < render::kMinSidePx || width > render::kMaxSidePx ||
      height > render::kMaxSidePx) {
    return invalid_argument("--size " + text + ": each side must be " + std::to_string(render::kMinSidePx) + ".." +
                            std::to_string(render::kMaxSidePx) + " pixels");
  }
  return Status::ok_status();
}

// The pack's horizontal extent (post centres, pack CRS metres).
struct Extent {
  double x0, x1, y0, y1;
  // How far (x, y) lies outside, metres (0 inside).
  double outside_m(double x, double y) const {
    return std::hypot(std::max({x0 - x, x - x1, 0.0}), std::max({y0 - y, y - y1, 0.0}));
  }
  // A rope may bulge a little past the edge (nothing holds it in), and the
  // picture widens to show that; more is a wrong file or CRS.
  double tolerance_m() const { return kPathOutsideFraction * std::max(x1 - x0, y1 - y0); }
  std::string describe(double x, double y) const {
    char text[240];
    std::snprintf(text, sizeof text, "(%.1f, %.1f) is %.0f m outside the pack (x %.1f..%.1f, y %.1f..%.1f%s)", x, y,
                  outside_m(x, y), x0, x1, y0, y1,
                  outside_m(x, y) > 0.5 * std::max(x1 - x0, y1 - y0) ? "; wrong CRS?" : "");
    return text;
  }
};
Extent extent_of(const fields::VolumeGeometry& g) {
  return {g.origin_x, g.origin_x + (g.nx - 1) * g.spacing_m, g.origin_y - (g.ny - 1) * g.spacing_m, g.origin_y};
}

struct RenderPath {
  std::vector<PathPoint> points;
  PathFormat format = PathFormat::text;
  bool said_unmet = false;  // the file says its requirements are not met (visvol plan's CSV and GeoJSON)
};

Result<RenderPath> read_render_path(const std::string& file, const std::string& crs_wkt,
                                    const fields::FieldSampler<PackLevel>& finest) {
  Result<PathFile> read = read_path_file(file, crs_wkt);
  if (!read.ok()) return read.status();
  if (!read->has_heights) {
    return invalid_argument(file +
                            ": points have no heights; render needs 'x y z' per line, a plan CSV or a "
                            "GeoJSON LineString with heights");
  }
  if (read->points.size() > kMaxRenderPathPoints) {
    return invalid_argument(file + ": " + std::to_string(read->points.size()) + " points; at most " +
                            std::to_string(kMaxRenderPathPoints));
  }
  const Extent e = extent_of(finest.level().geometry());
  RenderPath out;
  out.format = read->format;
  out.said_unmet = read->requirements_met.has_value() && !*read->requirements_met;
  out.points.reserve(read->points.size());
  for (std::size_t i = 0; i < read->points.size(); ++i) {
    const rt::Vec3& v = read->points[i];
    if (e.outside_m(v.x(), v.y()) > e.tolerance_m()) {
      return invalid_argument(file + ": point " + std::to_string(i + 1) + " " + e.describe(v.x(), v.y()) +
                              ", more than the " + std::to_string(std::lround(e.tolerance_m())) +
                              " m a path may stray");
    }
    // F_p from the file (`visvol plan` sampled the finest level), else sampled there now
    const double fp = read->fp.empty() ? std::clamp(finest.visibility(v.x(), v.y(), v.z()), 0.0, 1.0) : read->fp[i];
    out.points.push_back({v.x(), v.y(), v.z(), fp});
  }
  return out;
}

// Hidden-from and visible-to points, checked as `visvol plan` checks them:
// inside the pack and not below the terrain.
Result<std::vector<render::Marker>> markers_of(const RenderOptions& o, const fields::FieldSampler<PackLevel>& finest) {
  std::vector<render::Marker> out;
  const Extent e = extent_of(finest.level().geometry());
  for (int kind = 0; kind < 2; ++kind) {
    const auto& points = kind == 0 ? o.hidden_from : o.visible_to;
    const std::string option = kind == 0 ? "--hidden-from" : "--visible-to";
    for (const std::vector<double>& v : points) {
      if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        return invalid_argument(option + " takes three finite numbers X Y Z");
      }
      if (e.outside_m(v[0], v[1]) > 0) return invalid_argument(option + " " + e.describe(v[0], v[1]));
      VISVOL_RETURN_IF_ERROR(rt::check_observer_altitude(option, v[2]));  // as plan and check
      const double ground_m = finest.height(v[0], v[1]);
      if (v[2] < ground_m) {
        char text[160];
        std::snprintf(text, sizeof text, " (%.1f, %.1f, %.1f) is %.1f m below the terrain", v[0], v[1], v[2],
                      ground_m - v[2]);
        return invalid_argument(option + text);
      }
      out.push_back({kind == 0 ? render::MarkerKind::hidden_from : render::MarkerKind::visible_to, v[0], v[1], v[2]});
    }
  }
  if (out.size() > render::kDefaultMaxMarkers) {
    return invalid_argument(std::to_string(out.size()) + " hidden-from and visible-to points: at most " +
                            std::to_string(render::kDefaultMaxMarkers));
  }
  return out;
}

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// The options that need no pack, into the renderer's configuration.
Status configure(const RenderOptions& o, render::RendererConfig& config, render::View& view) {
  VISVOL_RETURN_IF_ERROR(parse_size(o.size, config.max_width_px, config.max_height_px));
  Result<render::View> v = render::parse_view(o.view);
  if (!v.ok()) return v.status();
  view = *v;
  if (o.compression < 0 || o.compression > 9) {
    return invalid_argument("--compression " + std::to_string(o.compression) + " is outside 0..9");
  }
  if (!std::isfinite(o.exaggeration) || o.exaggeration < 0 || o.exaggeration > 1000) {
    return invalid_argument("--exaggeration must be 0 (automatic) up to 1000");
  }
  if (o.height_given && !(std::isfinite(o.height_above_ground_m) && o.height_above_ground_m >= 0 &&
                          o.height_above_ground_m <= rt::kMaxObserverAltitudeM)) {
    return invalid_argument("--height-above-ground must be a number of metres from 0 to 100000");
  }
  if (!std::isfinite(o.fp_max) || o.fp_max < 0 || o.fp_max > 1) {
    return invalid_argument("--fp-max must be 0 (the field's largest F_p) up to 1");
  }
  config.png_compression_level = o.compression;
  config.vertical_exaggeration = o.exaggeration;
  config.fp_max = o.fp_max;
  if (!o.transfer.empty()) {
    Result<render::TransferFunction> tf = render::read_transfer_function(o.transfer);
    if (!tf.ok()) return tf.status();
    config.transfer = *tf;
  }
  return Status::ok_status();
}

// The PNG whole or not at all (temporary file, then rename).
Status write_png_file(const std::string& file, const std::uint8_t* data, std::size_t bytes) {
  Result<OutputFile> out = OutputFile::create(file);
  if (!out.ok()) return out.status();
  VISVOL_RETURN_IF_ERROR(out->write(data, bytes));
  return out->commit();
}

// What colours the picture, for the summary line.
std::string colouring(const RenderOptions& o, render::View view, const std::vector<PathPoint>& path) {
  char text[160];
  if (view == render::View::volume) return "F_p volume-rendered";
  if (view == render::View::slice) return "F_p on the slice along the path";
  if (o.height_given || path.empty()) {
    std::snprintf(text, sizeof text, "terrain coloured by F_p %.0f m above the ground",
                  o.height_given ? o.height_above_ground_m : render::kDefaultHeightAboveGroundM);
    return text;
  }
  double mean_m = 0;
  for (const PathPoint& p : path) mean_m += p.z_m / static_cast<double>(path.size());
  std::snprintf(text, sizeof text, "terrain coloured by F_p at %.0f m (the path's mean altitude)", mean_m);
  return text;
}

void print_path(const std::string& file, const RenderPath& path) {
  const char* format = path.format == PathFormat::geojson    ? "GeoJSON, WGS84 converted to the pack's CRS"
                       : path.format == PathFormat::plan_csv ? "plan CSV"
                                                             : "x y z text";
  const PathPoint &a = path.points.front(), &b = path.points.back();
  std::printf("path  %zu points from %s (%s): start (%.2f, %.2f, %.2f), end (%.2f, %.2f, %.2f) m\n", path.points.size(),
              file.c_str(), format, a.x_m, a.y_m, a.z_m, b.x_m, b.y_m, b.z_m);
  // a picture of a path passes from hand to hand: what its file says of it goes with it
  if (path.said_unmet) {
    std::printf(
        "note  %s says its requirements are NOT MET (see its unmet lines): this draws the path, it does "
        "not vouch for it\n",
        file.c_str());
  }
}

int run_render(const RenderOptions& o) {
  using Clock = std::chrono::steady_clock;
  render::RendererConfig config;
  render::View view = render::View::oblique;
  if (Status s = configure(o, config, view); !s.ok()) return fail("render", s);
  if (Status s = check_output_path(o.out); !s.ok()) return fail("render", s.with_context("-o"));
  if (Status s = output_is_no_input(o.out, "-o", {{"pack", o.pack}, {"--path", o.path}, {"--transfer", o.transfer}});
      !s.ok())
    return fail("render", s);
  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(o.pack);
  if (!pack.ok()) return fail("render", pack.status());
  Result<PackLevel> finest = PackLevel::open(*pack, 0);
  if (!finest.ok()) return fail("render", finest.status());
  const fields::FieldSampler<PackLevel> sampler(*finest);

  RenderPath path;
  if (!o.path.empty()) {
    Result<RenderPath> p = read_render_path(o.path, (*pack)->metadata().crs_wkt, sampler);
    if (!p.ok()) return fail("render", p.status());
    path = std::move(*p);
    config.max_path_vertices = std::max(config.max_path_vertices, path.points.size());
  }
  if (view == render::View::slice && path.points.empty()) {
    return fail("render", invalid_argument("--view slice needs --path"));
  }
  Result<std::vector<render::Marker>> markers = markers_of(o, sampler);
  if (!markers.ok()) return fail("render", markers.status());

  const Clock::time_point t_setup = Clock::now();
  Result<std::unique_ptr<render::Renderer>> renderer = render::Renderer::create(*pack, config);
  if (!renderer.ok()) return fail_render(renderer.status());
  const double setup_ms = ms_since(t_setup);

  render::Frame frame;
  frame.view = view;
  frame.width_px = config.max_width_px;
  frame.height_px = config.max_height_px;
  frame.path = path.points.empty() ? nullptr : path.points.data();
  frame.path_size = path.points.size();
  frame.markers = markers->empty() ? nullptr : markers->data();
  frame.marker_count = markers->size();
  if (o.height_given) frame.height_above_ground_m = o.height_above_ground_m;
  const Clock::time_point t_render = Clock::now();
  if (Status s = (*renderer)->render(frame); !s.ok()) return fail_render(s);
  const double render_ms = ms_since(t_render);

  std::vector<std::uint8_t> png(render::PngEncoder::worst_case_bytes(frame.width_px, frame.height_px));
  const Clock::time_point t_png = Clock::now();
  Result<std::size_t> bytes = (*renderer)->encode_png(png.data(), png.size());
  if (!bytes.ok()) return fail_render(bytes.status());
  const double png_ms = ms_since(t_png);
  if (Status s = write_png_file(o.out, png.data(), *bytes); !s.ok()) return fail("render", s);

  std::printf("wrote %s: %d x %d, %s view, %zu bytes; %s\n", o.out.c_str(), frame.width_px, frame.height_px,
              render::to_string(view), *bytes, colouring(o, view, path.points).c_str());
  if (!path.points.empty()) print_path(o.path, path);
  std::printf("time  setup %.0f ms, render %.1f ms, PNG %.1f ms (zlib level %d); %s\n", setup_ms, render_ms, png_ms,
              o.compression, (*renderer)->scene_info().gl_renderer.c_str());
  return kExitOk;
}

const char* const kRenderFooter = R"(
Views: oblique (from the south-south-west, 35 degrees up) and top (north up)
show the terrain as a lit mesh coloured by F_p at the path's mean altitude
(grey where the ground is above it), or --height-above-ground metres above the
ground; volume is F_p volume-rendered over the terrain (the paper's Fig. 3);
slice is F_p on the vertical surface along the path (distance across, height
up). Every picture has the F_p colour bar, a scale bar, a north arrow (3D
views), the path coloured by F_p (green disc: start, white square: end) and the
--hidden-from (black diamond) and --visible-to (magenta diamond) points.

Coordinates are the pack's CRS in metres, heights above the DEM's datum.
--path accepts what `visvol plan` writes: OUT.csv (columns x_m, y_m, z_m and
fp), OUT.geojson (a WGS84 LineString with heights, converted to the pack's
CRS), or text with one 'x y z' per line. Vertices may lie up to 5% of the
pack's larger side outside it; F_p comes from the file, else from the pack.

Transfer function file (--transfer): one control point per line, '#' starts a
comment, values separated by spaces or commas:
  colour  F R G B   colour at F (R, G, B in [0, 1]; 'color' also works)
  opacity F A       opacity A in [0, 1] that a ray collects across 1% of the
                    terrain's larger side where F_p is at F
F is F_p / the top of the colour scale (--fp-max), in [0, 1], strictly
increasing within each kind; at least one point of each kind, at most 64;
linear between points, the end values beyond them. The colours are also the
colour map of every view. Example (the default):
  colour 0 0.647 0 0.149
  colour 0.25 0.957 0.427 0.263
  colour 0.5 0.996 0.878 0.565
  colour 0.75 0.455 0.678 0.820
  colour 1 0.192 0.212 0.584
  opacity 0 0.2
  opacity 0.25 0.1
  opacity 0.5 0.02
  opacity 1 0

Exit status: 0 written, 1 the renderer failed (no OpenGL 3.3 context), 2 bad
arguments or input (the message names the file, line or option).)";

}  // namespace

Runner add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* c = app.add_subcommand("render", "Draw a thumbnail of the terrain, its visibility field and a path (PNG)");
  c->footer(kRenderFooter);
  c->add_option("PACK", o->pack, "Field pack (visvol build)")->required();
  c->add_option("--path", o->path,
                "Path: OUT.csv or OUT.geojson of `visvol plan`, or text 'x y z' per line (pack CRS, m); "
                "needed by --view slice");
  c->add_option("--size", o->size, "Picture size WIDTHxHEIGHT, pixels, 32..4096 a side")->capture_default_str();
  c->add_option("--view", o->view, "oblique, top, volume (F_p volume-rendered) or slice (along the path)")
      ->check(CLI::IsMember({"oblique", "top", "volume", "slice"}))
      ->capture_default_str();
  c->add_option("--transfer", o->transfer,
                "Transfer function file: 'colour F R G B' and 'opacity F A' lines (below); default red-yellow-blue");
  c->add_option("--hidden-from", o->hidden_from, "Mark a point X Y Z (m) the path hides from; repeatable")
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  c->add_option("--visible-to", o->visible_to, "Mark a point X Y Z (m) the path stays visible to; repeatable")
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  CLI::Option* height =
      c->add_option("--height-above-ground", o->height_above_ground_m,
                    "Colour the terrain by F_p this many metres above the ground (default: at the path's mean "
                    "altitude, or 30 m without a path)");
  c->add_option("--exaggeration", o->exaggeration,
                "Vertical exaggeration of the 3D views, 0..1000 (0: automatic, the field a fifth as tall as wide, "
                "1..10)")
      ->capture_default_str();
  c->add_option("--fp-max", o->fp_max,
                "F_p at the top of the colour scale, 0..1 (0: the field's largest); give one value to compare packs")
      ->capture_default_str();
  c->add_option("--compression", o->compression, "PNG zlib level 0..9 (1 is about 3x faster, a little larger)")
      ->capture_default_str();
  c->add_option("-o,--output", o->out, "Output PNG (written whole or not at all)")->required();
  return [o, height] {
    o->height_given = height->count() > 0;
    return run_render(*o);
  };
}

}  // namespace visvol::cli
