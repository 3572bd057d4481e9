// A level of detail held in memory with everything a sampler reads: terrain,
// F_p and the terrain force field band. For tests and in-memory planning; a
// console reads packs (storage::PackLevel) instead.
#pragma once

#include <vector>

#include "fields/pyramid.hpp"
#include "fields/terrain_force.hpp"

namespace visvol::fields {

class DenseLevel {
 public:
  DenseLevel(Heightfield terrain, DenseVolume field, const TffParams& tff);

  const VolumeGeometry& geometry() const { return field_.geometry; }
  float post(int i, int j) const { return terrain_.at(i, j); }
  float voxel(int i, int j, int k) const { return field_.at(i, j, k); }
  TffSample tff(int i, int j, int b) const {
    return tff_[(static_cast<std::size_t>(j) * static_cast<std::size_t>(tff_params_.band_levels) +
                 static_cast<std::size_t>(b)) *
                    static_cast<std::size_t>(terrain_.nx) +
                static_cast<std::size_t>(i)];
  }
  const TffParams& tff_params() const { return tff_params_; }
  const Heightfield& terrain() const { return terrain_; }
  const DenseVolume& field() const { return field_; }

 private:
  Heightfield terrain_;
  DenseVolume field_;
  TffParams tff_params_;
  std::vector<TffSample> tff_;
};

// Every level of detail of a heightfield, finest first.
Result<std::vector<DenseLevel>> build_dense_levels(const Heightfield& hf, const FieldParams& params, int levels,
                                                   const TffParams& tff);

}  // namespace visvol::fields
