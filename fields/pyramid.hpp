// Levels of detail (paper, section 3): coarser terrain with a larger range for
// global behaviour, finer terrain with a smaller range for local detail.
//
// Level 0 is the input. Level L+1 halves the terrain (2x2 means, see
// downsample2) and keeps the range in posts, so its range in metres doubles.
// All levels share level 0's vertical grid, so a height means the same level
// index everywhere. Observer weights are averaged like the terrain.
#pragma once

#include <vector>

#include "base/status.hpp"
#include "fields/field_params.hpp"
#include "fields/heightfield.hpp"
#include "fields/visibility_builder.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// The smallest grid a level may have, posts a side.
inline constexpr int kMinLevelPosts = 4;

struct LodInput {
  Heightfield terrain;
  FieldParams params;  // weights resampled, vertical grid fixed to level 0's
};

// Terrain and parameters of `levels` levels of detail (levels >= 1). Refuses
// when a level would be smaller than kMinLevelPosts a side.
Result<std::vector<LodInput>> lod_inputs(const Heightfield& hf, const FieldParams& params, int levels);

struct LodLevel {
  Heightfield terrain;
  DenseVolume field;
};

// Builds every level in memory; `progress` sees the fraction of all work.
Result<std::vector<LodLevel>> build_pyramid_dense(const Heightfield& hf, const FieldParams& params, int levels,
                                                  const ProgressFn& progress = {},
                                                  std::vector<BuildStats>* stats = nullptr);

}  // namespace visvol::fields
