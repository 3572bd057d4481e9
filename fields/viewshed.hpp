// A single-observer viewshed: the visibility hull of one post as a raster.
//
// Uses the same hull (and terrain model) as the visibility field, so it can be
// compared cell by cell with GRASS r.viewshed for the same observer.
#pragma once

#include <cstdint>
#include <vector>

#include "base/status.hpp"
#include "fields/heightfield.hpp"

namespace visvol::fields {

struct ViewshedParams {
  double observer_x = 0;  // world coordinates; snapped to the post whose pixel holds it
  double observer_y = 0;
  double observer_height_m = 2.0;  // eye above the ground
  double target_height_m = 0.0;    // target above the ground
  double max_distance_m = 0.0;     // 0: unlimited
  double curvature_coeff = 0.0;    // see FieldParams::curvature_coeff
  // Rings evaluated exactly (see FieldParams::exact_rings); one observer can
  // afford many.
  int exact_rings = 256;
};

inline constexpr std::uint8_t kViewshedHidden = 0;
inline constexpr std::uint8_t kViewshedVisible = 1;
inline constexpr std::uint8_t kViewshedOutside = 255;  // beyond max_distance_m (nodata)
// The largest max_distance_m accepted, m (100000 km: beyond any DEM).
inline constexpr double kMaxViewshedDistanceM = 1.0e8;

struct Viewshed {
  int nx = 0, ny = 0;
  int observer_i = 0, observer_j = 0;
  std::vector<std::uint8_t> value;  // ny rows of nx cells
  std::uint8_t at(int i, int j) const {
    return value[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)];
  }
};

Result<Viewshed> compute_viewshed(const Heightfield& hf, const ViewshedParams& params);

}  // namespace visvol::fields
