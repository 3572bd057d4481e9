// Parameters of the visibility field F_p (paper, section 3).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/heightfield.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// How far an observer sees.
//   none:   everywhere.
//   cube:   the paper's cube of influence: |di|, |dj| <= range_posts around the
//           post P and 0 <= z - z(P) <= 2 * range_posts * spacing (P on the ground).
//   sphere: a sensor range of range_posts * spacing metres around the observer's
//           eye (3D distance).
enum class RangeShape : std::uint8_t { none = 0, cube = 1, sphere = 2 };

const char* to_string(RangeShape shape);
// Parses "none", "cube" or "sphere".
Result<RangeShape> parse_range_shape(const std::string& text);

// Mean Earth radius used for curvature and refraction.
inline constexpr double kEarthRadiusM = 6371000.0;

// Heights of the voxel levels: z_k = z0_m + k * dz_m.
struct VerticalGrid {
  double z0_m = 0;
  double dz_m = 1;
};

// The largest working-memory limit a build accepts, MiB (16 TiB).
inline constexpr double kMaxMemoryMib = 16.0 * 1024 * 1024;

struct FieldParams {
  int nz = 128;               // voxel levels
  double ceiling_m = 300.0;   // height of the top level above the highest post
  double eye_height_m = 2.0;  // observer eye above its post
  RangeShape range_shape = RangeShape::cube;
  int range_posts = 64;  // cube half-side, or sphere radius in posts
  // Earth curvature and refraction: a point d metres from the observer appears
  // lowered by coeff * d^2 / (2 R). 0 is off; 0.85714 is the usual value
  // (refraction coefficient 1/7), as in GDAL and GRASS.
  double curvature_coeff = 0.0;
  // Observer likelihood W per post in [0, 1]; empty means 1 everywhere.
  std::vector<float> weights;
  // Rings evaluated exactly (every grid-line crossing) before the hull
  // recursion takes over; more is more accurate near sharp features and slower.
  int exact_rings = 16;
  int threads = 0;  // 0: all cores
  // Refuse builds whose working memory would exceed this.
  double max_memory_mib = 8192.0;
  // Fixed vertical grid; unset, levels run from the lowest post to the highest
  // post plus the ceiling. Coarser levels of detail reuse the finest level's.
  std::optional<VerticalGrid> vertical;
};

// Checks parameters against the heightfield (sizes, finite values, weights).
Status validate(const FieldParams& params, const Heightfield& hf);

// The voxel grid for a heightfield: levels from the lowest post to the highest
// post plus the ceiling.
VolumeGeometry volume_geometry(const Heightfield& hf, const FieldParams& params);

// The radius in posts the hull computation needs (range_posts, or the whole grid
// for RangeShape::none).
int hull_radius_posts(const FieldParams& params, const Heightfield& hf);

}  // namespace visvol::fields
