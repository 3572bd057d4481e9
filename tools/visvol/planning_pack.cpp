#include "planning_pack.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

namespace visvol::cli {

namespace {

// build.curvature_coeff of the metadata: 0 when absent, an error when it is
// not a number in 0..1.
Result<double> curvature_of(const storage::Pack& pack) {
  const nlohmann::json meta = nlohmann::json::parse(pack.metadata().json, nullptr, false);
  if (meta.is_discarded() || !meta.is_object()) return corrupt(pack.path() + ": metadata is not a JSON object");
  const auto build = meta.find("build");
  if (build == meta.end() || !build->is_object()) return 0.0;
  const auto c = build->find("curvature_coeff");
  if (c == build->end()) return 0.0;
  if (!c->is_number() || !(c->get<double>() >= 0 && c->get<double>() <= 1)) {
    return corrupt(pack.path() + ": metadata build.curvature_coeff is not a number in 0..1");
  }
  return c->get<double>();
}

}  // namespace

Result<PlanningPack> open_planning_pack(const std::string& path) {
  PlanningPack p;
  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(path);
  if (!pack.ok()) return pack.status();
  p.pack = *pack;
  for (int l = 0; l < p.pack->level_count(); ++l) {
    Result<storage::PackLevel> level = storage::PackLevel::open(p.pack, l);
    if (!level.ok()) return level.status();
    p.levels.push_back(std::move(*level));
  }
  Result<double> curvature = curvature_of(*p.pack);
  if (!curvature.ok()) return curvature.status();
  p.curvature_coeff = *curvature;
  p.bounds = storage::planning_bounds(*p.pack);
  VISVOL_RETURN_IF_ERROR(storage::check_planning_bounds(*p.pack));
  return p;
}

}  // namespace visvol::cli
