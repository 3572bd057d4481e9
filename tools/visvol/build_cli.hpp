// The options of a pack build and the steps before its first tile, shared by
// `visvol build` and `visvol-build-mpi` (the same build split among processes).
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/field_params.hpp"
#include "fields/gdal/dem_import.hpp"
#include "fields/heightfield.hpp"
#include "import_cli.hpp"
#include "storage/pack_build.hpp"

namespace visvol::cli {

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

// The DEM, the field's and the pack's options (not --output, --json,
// --json-file, whose wording differs between the commands).
void add_build_options(CLI::App* c, BuildOptions& o);

// What the build imports and records: the import options (--crop as given,
// or the crop --area needs) and the planning margin to record, if not the rule's.
// Memory a build holds per post of the imported grid, bytes, beyond the
// field's own working set (fields::plan_visibility_build), the larger of two
// moments with room to spare: the import's peak (GDAL's warp of SF North to
// 1 m posts: 2.98 GB for 155 M posts, 19 bytes a post), and the build's
// arrays once it runs (the heights and their level-0 copy 8, the coarser
// levels 1.3, the padded terrain and its ground levels 8, the observers'
// weights, eyes and range tops 16: about 34). Checked against --max-memory
// before the import reads anything.
inline constexpr int kBuildBytesPerPost = 48;
// Of those, what the build holds beside the field builder's working set
// while it runs (the heights, their level-0 copy, the coarser levels, the
// weights): the builder is given --max-memory less this.
inline constexpr int kHeldBytesPerPost = 16;

struct BuildInput {
  ImportCli import;
  std::optional<double> planning_margin_m;
};

// A build's terrain and field parameters, imported and checked.
struct PreparedBuild {
  BuildInput input;
  fields::ImportReport imported;
  fields::Heightfield terrain;
  fields::FieldParams params;
  std::vector<std::string> warnings;  // for the user, before the build (a CRS plans cannot convert)
};
Result<PreparedBuild> prepare_build(const BuildOptions& o);

// The field parameters for a terrain already imported, with the --weights
// raster read from its file, or these `weights` (a process sent them).
Result<fields::FieldParams> make_params(const BuildOptions& o, const fields::Heightfield& hf,
                                        const std::vector<float>* weights = nullptr);

// The pack's parameters.
storage::PackBuildParams pack_build_params(const BuildOptions& o, const PreparedBuild& b);

// The source description the pack records, with the area the crop came from.
std::string build_source_json(const BuildOptions& o, const PreparedBuild& b);

// The summary printed after a pack is written.
void print_pack_summary(const BuildOptions& o, const PreparedBuild& b, const storage::PackBuildReport& report);

}  // namespace visvol::cli
