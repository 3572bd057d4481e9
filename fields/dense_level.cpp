#include "fields/dense_level.hpp"

namespace visvol::fields {

DenseLevel::DenseLevel(Heightfield terrain, DenseVolume field, const TffParams& tff)
    : terrain_(std::move(terrain)), field_(std::move(field)), tff_params_(tff) {
  tff_.resize(static_cast<std::size_t>(terrain_.ny) * static_cast<std::size_t>(tff.band_levels) *
              static_cast<std::size_t>(terrain_.nx));
  terrain_force_rows(terrain_, tff_params_, 0, terrain_.ny, tff_.data(), nullptr);
}

Result<std::vector<DenseLevel>> build_dense_levels(const Heightfield& hf, const FieldParams& params, int levels,
                                                   const TffParams& tff) {
  VISVOL_RETURN_IF_ERROR(validate(tff, hf.spacing_m));
  Result<std::vector<LodLevel>> pyramid = build_pyramid_dense(hf, params, levels);
  if (!pyramid.ok()) return pyramid.status();
  std::vector<DenseLevel> out;
  out.reserve(pyramid->size());
  for (LodLevel& l : *pyramid) out.emplace_back(std::move(l.terrain), std::move(l.field), tff);
  return out;
}

}  // namespace visvol::fields
