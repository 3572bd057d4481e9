// A field pack opened for planning or checking a path: every level of
// detail (tiles checked), the Earth curvature coefficient it was built with
// (the sight lines use the same), and its planning bounds.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/volume.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::cli {

struct PlanningPack {
  std::shared_ptr<const storage::Pack> pack;
  std::vector<storage::PackLevel> levels;  // finest first
  double curvature_coeff = 0;
  fields::Bounds2D bounds;  // the trusted region, pack CRS metres
};

// Errors name the pack and the problem (a bad tile, metadata that is not what
// a pack writes).
Result<PlanningPack> open_planning_pack(const std::string& path);

}  // namespace visvol::cli
