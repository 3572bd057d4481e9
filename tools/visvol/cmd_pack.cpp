// visvol info | verify | sample | export: reading field packs (and DEMs for info).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/terminal_text.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/sampler.hpp"
#include "import_cli.hpp"
#include "io/atomic_file.hpp"
#include "io/input_file.hpp"
#include "io/json_text.hpp"
#include "pack_planner.hpp"  // the planner and sampler for packs: compiled in visvol_pack_planner
#include "storage/pack_reader.hpp"
#include "storage/volume_export.hpp"

namespace visvol::cli {

namespace {

using storage::Pack;
using storage::PackLevel;

// False also for what cannot be opened: the DEM reader then names the problem.
bool is_pack(const std::string& path) {
  Result<InputFile> in = InputFile::open(path);
  if (!in.ok()) return false;
  char magic[8] = {};
  return ::pread(in->fd(), magic, sizeof magic, 0) == static_cast<ssize_t>(sizeof magic) &&
         std::memcmp(magic, storage::kPackMagic, 8) == 0;
}

// A member of the metadata, or `fallback` when it is missing or of another type.
nlohmann::json member(const nlohmann::json& meta, const char* key, const nlohmann::json& fallback) {
  const auto it = meta.find(key);
  return it != meta.end() && it->type() == fallback.type() ? *it : fallback;
}

// The bounds as the metadata records them, and whether it did.
nlohmann::json info_planning_json(const storage::PlanningBounds& p) {
  nlohmann::json j = storage::planning_json(p);
  j["recorded"] = p.recorded;
  return j;
}

// "planning   x A..B, y C..D (margin M m)", saying so when derived or empty.
void print_planning(const storage::PlanningBounds& p) {
  if (p.box.empty()) {
    std::printf(
        "planning   none: a margin of %.0f m leaves nothing of the grid (derived; the pack "
        "predates recorded bounds)\n",
        p.margin_m);
    return;
  }
  std::printf("planning   %s%s\n", storage::describe(p).c_str(),
              p.recorded ? "" : ", derived: the pack predates recorded bounds");
}

nlohmann::json pack_info_json(const Pack& pack) {
  // Pack::open checked that the metadata is a JSON object.
  const nlohmann::json meta = nlohmann::json::parse(pack.metadata().json);
  const storage::LevelEntry& l0 = pack.level(0);
  nlohmann::json j;
  j["path"] = pack.path();
  j["file_bytes"] = pack.file_bytes();
  j["format_version"] = pack.header().version;
  j["nx"] = l0.nx;
  j["ny"] = l0.ny;
  j["nz"] = l0.nz;
  j["cell_size_m"] = l0.spacing_m;
  j["origin_x"] = l0.origin_x;
  j["origin_y"] = l0.origin_y;
  j["z0_m"] = l0.z0_m;
  j["dz_m"] = l0.dz_m;
  j["levels_of_detail"] = pack.level_count();
  j["crs_wkt"] = pack.metadata().crs_wkt;
  j["crs_name"] = pack.metadata().crs_name;
  j["visibility_encoding"] = pack.encoding() == storage::VisibilityEncoding::uint16 ? "uint16" : "float32";
  j["tff_band_offset_m"] = pack.header().band_offset_m;
  j["tff_band_levels"] = pack.header().band_levels;
  j["tiles"] = pack.tile_count();
  j["planning_bounds"] = info_planning_json(pack.metadata().planning);
  j["build"] = member(meta, "build", nlohmann::json::object());
  j["source"] = member(meta, "source", nlohmann::json::object());
  j["tool"] = pack.metadata().tool;
  j["created_utc"] = member(meta, "created_utc", "");
  for (int l = 0; l < pack.level_count(); ++l) {
    const storage::LevelEntry& e = pack.level(l);
    j["levels"].push_back({{"nx", e.nx},
                           {"ny", e.ny},
                           {"nz", e.nz},
                           {"spacing_m", e.spacing_m},
                           {"origin_x", e.origin_x},
                           {"origin_y", e.origin_y},
                           {"range_m", e.range_posts * e.spacing_m}});
  }
  return j;
}

void print_pack_info(const Pack& pack) {
  const nlohmann::json j = pack_info_json(pack);
  const storage::LevelEntry& l0 = pack.level(0);
  // the pack's own strings are input: shown so that none drives the terminal
  std::printf("pack       %s (format %u, %s)\n", terminal_safe(pack.path()).c_str(), pack.header().version,
              terminal_safe(j["tool"].get<std::string>(), 200).c_str());
  std::printf("size       %.1f MiB, %llu tiles, F_p %s\n", double(pack.file_bytes()) / 1048576.0,
              static_cast<unsigned long long>(pack.tile_count()), j["visibility_encoding"].get<std::string>().c_str());
  std::printf("crs        %s\n", pack.metadata().crs_name.empty()
                                     ? "(local metres)"
                                     : terminal_safe(pack.metadata().crs_name, 200).c_str());
  std::printf("grid       %d x %d posts x %d levels, %.2f m; post (0, 0) at (%.2f, %.2f)\n", l0.nx, l0.ny, l0.nz,
              l0.spacing_m, l0.origin_x, l0.origin_y);
  std::printf("heights    levels from %.2f m every %.3f m (top %.2f m)\n", l0.z0_m, l0.dz_m,
              l0.z0_m + (l0.nz - 1) * l0.dz_m);
  std::printf("tff band   +-%.1f m, %u samples a column\n", pack.header().band_offset_m, pack.header().band_levels);
  print_planning(pack.metadata().planning);
  std::printf("build      %s\n", terminal_safe(json_text(j["build"])).c_str());
  std::printf("source     %s\n", terminal_safe(json_text(j["source"])).c_str());
  std::printf("levels of detail:\n");
  for (int l = 0; l < pack.level_count(); ++l) {
    const storage::LevelEntry& e = pack.level(l);
    std::printf("  %d: %d x %d posts, %.1f m, range %.0f m\n", l, e.nx, e.ny, e.spacing_m, e.range_posts * e.spacing_m);
  }
}

struct InfoOptions {
  std::string path;
  bool json = false;
  ImportCli import;
  double max_memory_mib = 2048;
};

// What describing a DEM holds a post: its import's heights and GDAL's read
// (a 3.4 KB deflate GeoTIFF of 16384 x 16384 posts took 2.4 GB, 9 bytes a post).
constexpr int kInfoBytesPerPost = 16;

int run_info(const InfoOptions& o) {
  if (is_pack(o.path)) {
    Result<std::shared_ptr<const Pack>> pack = Pack::open(o.path);
    if (!pack.ok()) return fail("info", pack.status());
    if (o.json) {
      std::printf("%s\n", json_text(pack_info_json(**pack), 2).c_str());
    } else {
      print_pack_info(**pack);
    }
    return kExitOk;
  }
  // A DEM: what it is, and what import makes of it, within --max-memory
  // (refused from its header beyond).
  ImportCli import_cli = o.import;
  import_cli.max_posts = static_cast<std::size_t>(o.max_memory_mib * 1024.0 * 1024.0 / kInfoBytesPerPost);
  char reason[96];
  std::snprintf(reason, sizeof reason, "--max-memory %g MiB at %d bytes a post", o.max_memory_mib, kInfoBytesPerPost);
  import_cli.max_posts_reason = reason;
  fields::ImportReport rep;
  Result<fields::Heightfield> hf = import(o.path, import_cli, &rep);
  if (!hf.ok()) return fail("info", hf.status());
  const fields::HeightRange hr = fields::height_range(*hf);
  const double* gt = rep.source.geotransform;
  if (o.json) {
    nlohmann::json j;
    j["path"] = o.path;
    j["driver"] = rep.source.driver;
    j["source"] = {{"nx", rep.source.nx},
                   {"ny", rep.source.ny},
                   {"pixel_size", {gt[1], gt[5]}},
                   {"crs", rep.source.crs_name},
                   {"vertical_unit", rep.source.vertical_unit},
                   {"nodata", rep.source.has_nodata ? nlohmann::json(rep.source.nodata) : nlohmann::json()}};
    j["imported"] = {{"nx", hf->nx},
                     {"ny", hf->ny},
                     {"cell_size_m", hf->spacing_m},
                     {"origin_x", hf->origin_x},
                     {"origin_y", hf->origin_y},
                     {"crs", rep.output_crs},
                     {"crs_wkt", hf->crs_wkt},
                     {"height_min_m", hr.min_m},
                     {"height_max_m", hr.max_m},
                     {"steps", rep.steps}};
    std::printf("%s\n", json_text(j, 2).c_str());
    return kExitOk;
  }
  // the DEM's own strings (its CRS's name, its unit) are input, shown escaped
  std::printf("DEM        %s (%s)\n", terminal_safe(o.path).c_str(), rep.source.driver.c_str());
  std::printf("source     %d x %d, pixel %.6g x %.6g, %s, heights in %s%s\n", rep.source.nx, rep.source.ny, gt[1],
              -gt[5], rep.source.crs_name.empty() ? "no CRS" : terminal_safe(rep.source.crs_name, 200).c_str(),
              rep.source.vertical_unit.empty() ? "m" : terminal_safe(rep.source.vertical_unit, 80).c_str(),
              rep.source.has_nodata ? (", nodata " + std::to_string(rep.source.nodata)).c_str() : "");
  if (!rep.steps.empty()) std::printf("import     %s\n", terminal_safe(rep.steps).c_str());
  std::printf("terrain    %d x %d posts, %.2f m spacing, %s\n", hf->nx, hf->ny, hf->spacing_m,
              terminal_safe(rep.output_crs, 200).c_str());
  std::printf("           post (0, 0) at (%.2f, %.2f), heights %.1f..%.1f m\n", hf->origin_x, hf->origin_y, hr.min_m,
              hr.max_m);
  return kExitOk;
}

int run_verify(const std::string& path) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  if (!pack.ok()) return fail("verify", pack.status());
  Progress progress("verifying " + path);
  const Status st = (*pack)->verify([&](double f) { progress.update(f); });
  if (!st.ok()) return fail("verify", st);
  progress.finish();
  std::printf("ok: %llu tiles and the tables of %s hold their checksums (%.1f MiB)\n",
              static_cast<unsigned long long>((*pack)->tile_count()), path.c_str(),
              double((*pack)->file_bytes()) / 1048576.0);
  return kExitOk;
}

struct SampleOptions {
  std::string path;
  std::string layer = "visibility";
  int lod = 0;
};

// A point's line is a few dozen bytes.
constexpr std::size_t kMaxSampleLineBytes = 4096;

// std::getline with a bound: false at the end of the input; `too_long` when
// the line reached `max_bytes` without its end (what was read is dropped).
bool read_bounded_line(std::istream& in, std::string& line, std::size_t max_bytes, bool& too_long) {
  line.clear();
  too_long = false;
  int c = 0;
  while ((c = in.get()) != std::char_traits<char>::eof()) {
    if (c == '\n') return true;
    if (line.size() == max_bytes) {
      too_long = true;
      return true;
    }
    line.push_back(static_cast<char>(c));
  }
  return !line.empty();
}

int run_sample(const SampleOptions& o) {
  if (o.layer != "visibility" && o.layer != "gradient" && o.layer != "height" && o.layer != "tff") {
    return fail("sample",
                invalid_argument("--layer '" + o.layer + "' is not one of visibility, gradient, height, tff"));
  }
  Result<std::shared_ptr<const Pack>> pack = Pack::open(o.path);
  if (!pack.ok()) return fail("sample", pack.status());
  Result<PackLevel> level = PackLevel::open(*pack, o.lod);
  if (!level.ok()) return fail("sample", level.status());
  const fields::FieldSampler<PackLevel> sampler(*level);
  const fields::VolumeGeometry& g = level->geometry();
  const double x_max = g.origin_x + (g.nx - 1) * g.spacing_m;
  const double y_min = g.origin_y - (g.ny - 1) * g.spacing_m;
  std::string line;
  long line_no = 0, bad = 0;
  bool too_long = false;
  while (read_bounded_line(std::cin, line, kMaxSampleLineBytes, too_long)) {
    ++line_no;
    if (too_long) {
      // /dev/zero on stdin grew one line to gigabytes: no text of points
      return fail("sample", invalid_argument("stdin line " + std::to_string(line_no) + " is longer than " +
                                             std::to_string(kMaxSampleLineBytes) +
                                             " bytes: not a line 'x y z' (is the input text?)"));
    }
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream in(line);
    double x, y, z;
    std::string rest;
    if (!(in >> x >> y >> z) || (in >> rest) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      std::fprintf(stderr, "visvol sample: line %ld: expected three finite numbers 'x y z', got '%s'\n", line_no,
                   terminal_safe(line, 80).c_str());
      std::printf("nan\n");
      ++bad;
      continue;
    }
    if (x < g.origin_x || x > x_max || y < y_min || y > g.origin_y) {
      std::fprintf(stderr, "visvol sample: line %ld: (%.3f, %.3f) is outside the pack (x %.3f..%.3f, y %.3f..%.3f)\n",
                   line_no, x, y, g.origin_x, x_max, y_min, g.origin_y);
      std::printf("nan\n");
      ++bad;
      continue;
    }
    if (o.layer == "visibility") {
      std::printf("%.6f\n", sampler.visibility(x, y, z));
    } else if (o.layer == "height") {
      std::printf("%.3f\n", sampler.height(x, y));
    } else if (o.layer == "gradient") {
      const Eigen::Vector3d d = sampler.gradient(x, y, z);
      std::printf("%.6e %.6e %.6e\n", d.x(), d.y(), d.z());
    } else {
      const fields::TffSample s = sampler.terrain_force(x, y, z);
      std::printf("%.3f %.3f %.3f %.3f\n", s.dx_m, s.dy_m, s.dz_m, s.signed_distance_m);
    }
    // a line answered as it is asked, when a program feeds the points through a pipe
    std::fflush(stdout);
  }
  return bad == 0 ? kExitOk : kExitUsage;
}

struct ExportOptions {
  std::string path, out;
  std::string layer = "visibility";
  std::string format = "mhd";
  int lod = 0;
};

int run_export(const ExportOptions& o) {
  Result<storage::ExportLayer> layer = storage::parse_export_layer(o.layer);
  if (!layer.ok()) return fail("export", layer.status());
  Result<storage::ExportFormat> format = storage::parse_export_format(o.format);
  if (!format.ok()) return fail("export", format.status());
  if (Status s = check_output_path(o.out); !s.ok()) return fail("export", s.with_context("-o"));
  if (Status s = output_is_no_input(o.out, "-o", {{"pack", o.path}}); !s.ok()) return fail("export", s);
  Result<std::shared_ptr<const Pack>> pack = Pack::open(o.path);
  if (!pack.ok()) return fail("export", pack.status());
  Result<PackLevel> level = PackLevel::open(*pack, o.lod);
  if (!level.ok()) return fail("export", level.status());
  const storage::ExportedVolume v = storage::extract_layer(*level, *layer);
  const Status st = storage::write_volume(o.out, v, *format);
  if (!st.ok()) return fail("export", st);
  std::printf(
      "wrote %s: %s, %d x %d x %d x %d component(s), origin (%.2f, %.2f, %.2f) m, spacing "
      "(%.2f, %.2f, %.3f) m\n",
      o.out.c_str(), v.name.c_str(), v.nx, v.ny, v.nz, v.components, v.origin[0], v.origin[1], v.origin[2],
      v.spacing[0], v.spacing[1], v.spacing[2]);
  return kExitOk;
}

}  // namespace

Runner add_info_command(CLI::App& app) {
  auto o = std::make_shared<InfoOptions>();
  CLI::App* c = app.add_subcommand("info", "Describe a field pack, or a DEM and what import makes of it");
  c->add_option("FILE", o->path, "Field pack or DEM")->required();
  c->add_flag("--json", o->json, "Print one JSON object");
  add_import_options(c, o->import);
  c->add_option("--max-memory", o->max_memory_mib,
                "A DEM: refuse one whose import needs more memory, MiB (16 bytes a post, checked before it is read)")
      ->check(CLI::Range(1.0, 16777216.0))
      ->capture_default_str();
  return [o] { return run_info(*o); };
}

Runner add_verify_command(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* c = app.add_subcommand("verify", "Check every checksum of a field pack (exit 0 only if all hold)");
  c->add_option("PACK", *path, "Field pack")->required();
  return [path] { return run_verify(*path); };
}

Runner add_sample_command(CLI::App& app) {
  auto o = std::make_shared<SampleOptions>();
  CLI::App* c = app.add_subcommand(
      "sample", "Read lines 'x y z' (world metres in the pack's CRS) on stdin and print one line per point");
  c->add_option("PACK", o->path, "Field pack")->required();
  c->add_option("--layer", o->layer,
                "visibility (F_p), gradient (per metre: gx gy gz), height (m), tff (outward "
                "displacement dx dy dz and signed distance, m)")
      ->capture_default_str();
  c->add_option("--lod", o->lod, "Level of detail (0 is the finest)")->capture_default_str();
  return [o] { return run_sample(*o); };
}

Runner add_export_command(CLI::App& app) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* c =
      app.add_subcommand("export", "Write a layer as MetaImage or VTK image data for ParaView, 3D Slicer, VolView");
  c->add_option("PACK", o->path, "Field pack")->required();
  c->add_option("--layer", o->layer, "visibility, gradient, height, area or tff")->capture_default_str();
  c->add_option("--lod", o->lod, "Level of detail (0 is the finest)")->capture_default_str();
  c->add_option("--format", o->format, "mhd (MetaImage) or vti (VTK image data)")->capture_default_str();
  c->add_option("-o,--output", o->out, "Output file")->required();
  return [o] { return run_export(*o); };
}

}  // namespace visvol::cli
