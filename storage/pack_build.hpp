// Builds a field pack from a heightfield: every level of detail's terrain,
// area factor, visibility field F_p and terrain force field, streamed tile by
// tile to a PackWriter. Working memory is one band of 16 rows of the field
// plus the builder's own window: a field far larger than memory is fine.
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
#include "fields/terrain_force.hpp"
#include "fields/visibility_builder.hpp"
#include "storage/pack_format.hpp"
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

}  // namespace visvol::storage
