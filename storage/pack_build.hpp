// Builds a field pack from a heightfield: every level of detail's terrain,
// area factor, visibility field F_p and terrain force field, streamed tile by
// tile to a PackWriter. Working memory is one band of 16 rows of the field
// plus the builder's own window (split by observers, also the rows waiting for
// other shares' sums): a field far larger than memory is fine.
//
// A build may be split among processes (visvol-build-mpi): each builds a
// share of every level's rows into its own tiles, and one of them writes the
// tables. The pack is the same byte for byte however it is split (every tile
// is built from the whole terrain; F_p's sums are integers).
//
// Offline only (threads, blocking I/O).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/field_params.hpp"
#include "fields/heightfield.hpp"
#include "fields/pyramid.hpp"
#include "fields/terrain_force.hpp"
#include "fields/visibility_builder.hpp"
#include "storage/pack_format.hpp"
#include "storage/pack_writer.hpp"
#include "storage/planning_bounds.hpp"

namespace visvol::storage {

struct PackBuildParams {
  fields::FieldParams field;
  int lod_levels = 3;
  VisibilityEncoding encoding = VisibilityEncoding::uint16;
  fields::TffParams tff;
  std::string crs_name;  // recorded beside the WKT for people reading `visvol info`
  // Planning margin, m (>= 0): overrides the rule's margin (planning_bounds.hpp).
  std::optional<double> planning_margin_m;
};

struct PackBuildReport {
  std::vector<fields::BuildStats> levels;  // visibility field per level
  double tff_s = 0;                        // terrain force field, all levels
  double wall_s = 0;
  std::uint64_t file_bytes = 0;
  PlanningBounds planning;  // as recorded in the metadata
};

// The project's version string, recorded in every pack.
const char* tool_version();

// `source_json` is a JSON object describing where the terrain came from (path,
// hash, import options); it is stored in the metadata under "source". The
// planning bounds are recorded under "planning_bounds"; a build whose bounds
// would be empty is refused before anything is written.
Status build_pack(const fields::Heightfield& hf, const PackBuildParams& params, const std::string& source_json,
                  const std::string& out_path, const fields::ProgressFn& progress = {},
                  PackBuildReport* report = nullptr);

// The pieces of build_pack, for a build split among processes.

// Everything a build decides before its first tile: the levels of detail, the
// pack's layout and its planning bounds. Refuses what build_pack refuses
// (parameters, memory plans, empty planning bounds) before anything is written.
struct PackPlan {
  std::vector<fields::LodInput> inputs;
  PackLayout layout;
  PlanningBounds planning;
};
Result<PackPlan> plan_pack(const fields::Heightfield& hf, const PackBuildParams& params);

// Share `index` of a build split `count` ways: its band of each level's tile
// rows (16-row bricks of F_p and the terrain force field, 64-row height and
// area tiles), about equal numbers of them. {0, 1} is the whole pack; the
// shares 0..count-1 together write every tile once.
//
// Without `exchange`, a share computes the hulls of every observer within
// range of its band (split by rows: shares run alone, in any order). With it,
// only its band's observers, and the sums over rows of other shares' bands
// travel through it (split by observers: fields::build_visibility_share;
// every share runs at once, each with its own end of one exchange).
struct BuildShare {
  int index = 0;
  int count = 1;
  fields::RowExchange* exchange = nullptr;
};
Status validate(const BuildShare& share);

// Tile rows [first, end) of a layer `tiles_y` rows high that a share builds
// (empty when there are fewer rows than shares).
struct TileRows {
  int first = 0, end = 0;
};
TileRows share_tile_rows(int tiles_y, BuildShare share);

// The rows of F_p a share builds at a level `nx` x `ny` posts: its brick
// rows', in posts (empty when it has none).
fields::RowBand share_field_rows(int nx, int ny, BuildShare share);

// Builds one share's tiles into `sink` (a PackWriter of plan.layout, or one
// that writes at its placement). `report` gets this share's figures.
Status build_pack_share(const PackPlan& plan, const PackBuildParams& params, BuildShare share, TileSink& sink,
                        const fields::ProgressFn& progress = {}, PackBuildReport* report = nullptr);

// The pack's metadata (JSON): `source_json` must be a JSON object or empty.
Result<std::string> pack_metadata(const fields::Heightfield& hf, const PackBuildParams& params,
                                  const std::string& source_json, const PackPlan& plan);

}  // namespace visvol::storage
