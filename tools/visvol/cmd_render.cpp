// visvol render PACK [--path FILE] [--size WxH] [--view V] [--transfer FILE] -o OUT.png:
// a thumbnail of the terrain, its visibility field and a path (drivers/render).
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "commands.hpp"
#include "drivers/render/png_encoder.hpp"
#include "drivers/render/renderer.hpp"
#include "fields/sampler.hpp"
#include "path_io.hpp"
#include "rt/base/atomic_file.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::cli {

namespace {

using render::PathPoint;
using storage::PackLevel;

struct RenderOptions {
  std::string pack, path, size = "512x384", view = "oblique", transfer, out;
  std::vector<std::vector<double>> hidden_from, visible_to;
  double height_above_ground_m = -1;  // < 0: not given
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

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    const std::size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
    out.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
  }
  return out;
}

bool to_number(const std::string& s, double& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && errno != ERANGE && std::isfinite(v);
}

// The CSV `visvol plan` writes: a header naming x_m, y_m, z_m and (optional) fp.
// Returns false (and nothing in `out`) when the file has no such header.
Result<bool> read_plan_csv(const std::string& file, std::vector<PathPoint>& out, bool& has_fp) {
  std::ifstream in(file);
  if (!in) return io_error(file + ": " + std::strerror(errno));
  std::string line;
  int line_no = 0;
  int col_x = -1, col_y = -1, col_z = -1, col_fp = -1;
  std::size_t columns = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
    const std::vector<std::string> cells = split_commas(line);
    if (columns == 0) {
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const int ci = static_cast<int>(c);
        if (cells[c] == "x_m") col_x = ci;
        if (cells[c] == "y_m") col_y = ci;
        if (cells[c] == "z_m") col_z = ci;
        if (cells[c] == "fp") col_fp = ci;
      }
      if (col_x < 0) return false;  // not a plan CSV: plain "x y z" text
      if (col_y < 0 || col_z < 0) {
        return invalid_argument(file + ": line " + std::to_string(line_no) + ": the header names x_m but not " +
                                (col_y < 0 ? "y_m" : "z_m"));
      }
      columns = cells.size();
      continue;
    }
    const std::string where = file + ": line " + std::to_string(line_no) + ": ";
    if (cells.size() != columns) {
      return invalid_argument(where + std::to_string(cells.size()) + " columns, the header has " +
                              std::to_string(columns));
    }
    PathPoint p{0, 0, 0, 0};
    const std::pair<int, double*> wanted[] = {{col_x, &p.x_m}, {col_y, &p.y_m}, {col_z, &p.z_m}, {col_fp, &p.fp}};
    for (const auto& [col, dst] : wanted) {
      if (col < 0) continue;
      const std::string& cell = cells[static_cast<std::size_t>(col)];
      if (!to_number(cell, *dst)) return invalid_argument(where + "'" + cell + "' is not a finite number");
    }
    if (col_fp >= 0 && !(p.fp >= 0 && p.fp <= 1)) {
      return invalid_argument(where + "fp " + cells[static_cast<std::size_t>(col_fp)] + " is outside [0, 1]");
    }
    out.push_back(p);
  }
  if (columns == 0) return false;
  if (out.size() < 2) return invalid_argument(file + ": fewer than 2 points");
  has_fp = col_fp >= 0;
  return true;
}

// The pack's horizontal extent. Points outside are drawn (a rope may bulge
// past the edge, and the picture widens to show it); points more than half
// the pack's size outside mean a wrong CRS or file.
struct Extent {
  double x0, x1, y0, y1;
  bool near(double x, double y) const {
    const double margin = 0.5 * std::max(x1 - x0, y1 - y0);
    return x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin;
  }
  std::string describe(double x, double y) const {
    char text[200];
    std::snprintf(text, sizeof text,
                  "(%.1f, %.1f) is far outside the pack (x %.1f..%.1f, y %.1f..%.1f; wrong CRS?)", x, y, x0, x1, y0,
                  y1);
    return text;
  }
};
Extent extent_of(const fields::VolumeGeometry& g) {
  return {g.origin_x, g.origin_x + (g.nx - 1) * g.spacing_m, g.origin_y - (g.ny - 1) * g.spacing_m, g.origin_y};
}

Result<std::vector<PathPoint>> read_render_path(const std::string& file,
                                                const fields::FieldSampler<PackLevel>& finest) {
  std::vector<PathPoint> points;
  bool has_fp = false;
  Result<bool> csv = read_plan_csv(file, points, has_fp);
  if (!csv.ok()) return csv.status();
  if (!*csv) {
    Result<PathFile> text = read_path_file(file);
    if (!text.ok()) return text.status();
    if (!text->has_heights) {
      return invalid_argument(file + ": points have no heights; render needs 'x y z' per line (or a plan CSV)");
    }
    for (const rt::Vec3& v : text->points) points.push_back({v.x(), v.y(), v.z(), 0});
  }
  const Extent e = extent_of(finest.level().geometry());
  for (std::size_t i = 0; i < points.size(); ++i) {
    PathPoint& p = points[i];
    if (!e.near(p.x_m, p.y_m)) {
      return invalid_argument(file + ": point " + std::to_string(i + 1) + " " + e.describe(p.x_m, p.y_m));
    }
    // F_p on the finest level, as `visvol plan` reports it
    if (!has_fp) p.fp = std::clamp(finest.visibility(p.x_m, p.y_m, p.z_m), 0.0, 1.0);
  }
  return points;
}

Result<std::vector<render::Marker>> markers_of(const RenderOptions& o, const fields::VolumeGeometry& g) {
  std::vector<render::Marker> out;
  const Extent e = extent_of(g);
  for (int kind = 0; kind < 2; ++kind) {
    const auto& points = kind == 0 ? o.hidden_from : o.visible_to;
    const char* option = kind == 0 ? "--hidden-from" : "--visible-to";
    for (const std::vector<double>& v : points) {
      if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        return invalid_argument(std::string(option) + " takes three finite numbers X Y Z");
      }
      if (!e.near(v[0], v[1])) return invalid_argument(std::string(option) + " " + e.describe(v[0], v[1]));
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

int run_render(const RenderOptions& o) {
  using Clock = std::chrono::steady_clock;
  int width = 0, height = 0;
  if (Status s = parse_size(o.size, width, height); !s.ok()) return fail("render", s);
  Result<render::View> view = render::parse_view(o.view);
  if (!view.ok()) return fail("render", view.status());
  if (o.compression < 0 || o.compression > 9) {
    return fail("render", invalid_argument("--compression " + std::to_string(o.compression) + " is outside 0..9"));
  }
  if (!std::isfinite(o.exaggeration) || o.exaggeration < 0 || o.exaggeration > 1000) {
    return fail("render", invalid_argument("--exaggeration must be 0 (automatic) up to 1000"));
  }
  if (o.height_above_ground_m != -1 && !(std::isfinite(o.height_above_ground_m) && o.height_above_ground_m >= 0)) {
    return fail("render", invalid_argument("--height-above-ground must be a finite number of metres, 0 or more"));
  }
  if (!std::isfinite(o.fp_max) || o.fp_max < 0 || o.fp_max > 1) {
    return fail("render", invalid_argument("--fp-max must be 0 (the field's largest F_p) up to 1"));
  }
  render::RendererConfig config;
  config.max_width_px = width;
  config.max_height_px = height;
  config.png_compression_level = o.compression;
  config.vertical_exaggeration = o.exaggeration;
  config.fp_max = o.fp_max;
  if (!o.transfer.empty()) {
    Result<render::TransferFunction> tf = render::read_transfer_function(o.transfer);
    if (!tf.ok()) return fail("render", tf.status());
    config.transfer = *tf;
  }

  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(o.pack);
  if (!pack.ok()) return fail("render", pack.status());
  Result<PackLevel> finest = PackLevel::open(*pack, 0);
  if (!finest.ok()) return fail("render", finest.status());
  const fields::FieldSampler<PackLevel> sampler(*finest);

  std::vector<PathPoint> path;
  if (!o.path.empty()) {
    Result<std::vector<PathPoint>> p = read_render_path(o.path, sampler);
    if (!p.ok()) return fail("render", p.status());
    path = std::move(*p);
    config.max_path_vertices = std::max(config.max_path_vertices, path.size());
  }
  if (*view == render::View::slice && path.empty()) {
    return fail("render", invalid_argument("--view slice needs --path"));
  }
  Result<std::vector<render::Marker>> markers = markers_of(o, finest->geometry());
  if (!markers.ok()) return fail("render", markers.status());

  const Clock::time_point t_setup = Clock::now();
  Result<std::unique_ptr<render::Renderer>> renderer = render::Renderer::create(*pack, config);
  if (!renderer.ok()) return fail_render(renderer.status());
  const double setup_ms = ms_since(t_setup);

  render::Frame frame;
  frame.view = *view;
  frame.width_px = width;
  frame.height_px = height;
  frame.path = path.empty() ? nullptr : path.data();
  frame.path_size = path.size();
  frame.markers = markers->empty() ? nullptr : markers->data();
  frame.marker_count = markers->size();
  if (o.height_above_ground_m >= 0) frame.height_above_ground_m = o.height_above_ground_m;
  const Clock::time_point t_render = Clock::now();
  if (Status s = (*renderer)->render(frame); !s.ok()) return fail_render(s);
  const double render_ms = ms_since(t_render);

  std::vector<std::uint8_t> png(render::PngEncoder::worst_case_bytes(width, height));
  const Clock::time_point t_png = Clock::now();
  Result<std::size_t> bytes = (*renderer)->encode_png(png.data(), png.size());
  if (!bytes.ok()) return fail_render(bytes.status());
  const double png_ms = ms_since(t_png);

  const std::string temp = temp_path_for(o.out);
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(*bytes));
    out.flush();
    if (!out) {
      discard_file(temp);
      return fail("render", io_error(o.out + ": cannot write"));
    }
  }
  if (Status s = commit_file(temp, o.out); !s.ok()) return fail("render", s);

  std::string colour;
  char text[160];
  if (*view == render::View::volume || *view == render::View::slice) {
    colour = *view == render::View::volume ? "F_p volume-rendered" : "F_p on the slice along the path";
  } else if (o.height_above_ground_m >= 0 || path.empty()) {
    std::snprintf(text, sizeof text, "terrain coloured by F_p %.0f m above the ground",
                  o.height_above_ground_m >= 0 ? o.height_above_ground_m : render::kDefaultHeightAboveGroundM);
    colour = text;
  } else {
    double mean = 0;
    for (const PathPoint& p : path) mean += p.z_m / static_cast<double>(path.size());
    std::snprintf(text, sizeof text, "terrain coloured by F_p at %.0f m (the path's mean altitude)", mean);
    colour = text;
  }
  std::printf("wrote %s: %d x %d, %s view, %zu bytes; %s\n", o.out.c_str(), width, height,
              render::to_string(*view), *bytes, colour.c_str());
  std::printf("time  setup %.0f ms, render %.1f ms, PNG %.1f ms (zlib level %d); %s\n", setup_ms, render_ms, png_ms,
              o.compression, (*renderer)->scene_info().gl_renderer.c_str());
  return kExitOk;
}

}  // namespace

Runner add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* c = app.add_subcommand("render", "Draw a thumbnail of the terrain, its visibility field and a path (PNG)");
  c->add_option("PACK", o->pack, "Field pack")->required();
  c->add_option("--path", o->path,
                "Path: the CSV `visvol plan` writes, or text 'x y z' per line (pack CRS, m)");
  c->add_option("--size", o->size, "Picture size WIDTHxHEIGHT in pixels (32..4096 a side)")->capture_default_str();
  c->add_option("--view", o->view, "oblique, top, volume (F_p volume-rendered) or slice (along the path)")
      ->check(CLI::IsMember({"oblique", "top", "volume", "slice"}))
      ->capture_default_str();
  c->add_option("--transfer", o->transfer,
                "Transfer function file: lines 'colour F R G B' and 'opacity F A' (all in [0, 1])");
  c->add_option("--hidden-from", o->hidden_from, "Mark a point X Y Z the path hides from (repeatable)")
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  c->add_option("--visible-to", o->visible_to, "Mark a point X Y Z the path stays visible to (repeatable)")
      ->expected(3)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  c->add_option("--height-above-ground", o->height_above_ground_m,
                "Colour the terrain by F_p this many metres above the ground (default: at the path's mean "
                "altitude, or 30 m without a path)");
  c->add_option("--exaggeration", o->exaggeration, "Vertical exaggeration of the 3D views (0: automatic)")
      ->capture_default_str();
  c->add_option("--fp-max", o->fp_max,
                "F_p at the top of the colour scale (0: the field's largest), to compare packs")
      ->capture_default_str();
  c->add_option("--compression", o->compression, "PNG zlib level 0..9")->capture_default_str();
  c->add_option("-o,--output", o->out, "Output PNG")->required();
  return [o] { return run_render(*o); };
}

}  // namespace visvol::cli
