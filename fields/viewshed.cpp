#include "fields/viewshed.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fields/hull_kernel.hpp"

namespace visvol::fields {

Result<Viewshed> compute_viewshed(const Heightfield& hf, const ViewshedParams& p) {
  VISVOL_RETURN_IF_ERROR(validate(hf, "DEM"));
  std::ostringstream msg;
  if (!std::isfinite(p.observer_x) || !std::isfinite(p.observer_y)) {
    return invalid_argument("observer: coordinates must be finite");
  }
  // The post whose pixel holds the observer (pixel-is-area).
  const double fi = std::floor(hf.i_of(p.observer_x) + 0.5);
  const double fj = std::floor(hf.j_of(p.observer_y) + 0.5);
  if (fi < 0 || fj < 0 || fi >= hf.nx || fj >= hf.ny) {
    msg.precision(12);
    msg << "observer (" << p.observer_x << ", " << p.observer_y << ") is outside the DEM";
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(p.observer_height_m) || !std::isfinite(p.target_height_m) || p.observer_height_m < -1.0e4 ||
      p.observer_height_m > 1.0e5 || p.target_height_m < -1.0e4 || p.target_height_m > 1.0e5) {
    return invalid_argument("observer or target height is not a finite height within 100 km");
  }
  if (!std::isfinite(p.max_distance_m) || p.max_distance_m < 0 || p.max_distance_m > kMaxViewshedDistanceM) {
    msg.precision(6);
    msg << "max distance: " << p.max_distance_m << " m is outside 0.." << kMaxViewshedDistanceM << " m (0: unlimited)";
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(p.curvature_coeff) || p.curvature_coeff < 0 || p.curvature_coeff > 1) {
    return invalid_argument("curvature coefficient must be in [0, 1]");
  }
  if (p.exact_rings < 1 || p.exact_rings > kMaxPostsPerSide) {
    return invalid_argument("exact rings: " + std::to_string(p.exact_rings) + " is outside 1.." +
                            std::to_string(kMaxPostsPerSide));
  }
  Viewshed vs;
  vs.nx = hf.nx;
  vs.ny = hf.ny;
  vs.observer_i = static_cast<int>(fi);
  vs.observer_j = static_cast<int>(fj);
  const int full = std::max(hf.nx, hf.ny) - 1;
  // In posts, clamped to the grid before it becomes an int.
  const int radius = p.max_distance_m > 0
                         ? static_cast<int>(std::min<double>(full, std::ceil(p.max_distance_m / hf.spacing_m)))
                         : full;

  if (radius > kMaxHullRing) {
    msg.str("");
    msg << "viewshed: " << radius << " posts from the observer is over the " << kMaxHullRing
        << " a horizon reaches; give a --max-distance of at most " << kMaxHullRing * hf.spacing_m << " m";
    return invalid_argument(msg.str());
  }

  VolumeGeometry g;  // only the ground levels of the padding are unused here
  g.nz = 1;
  g.z0_m = 0;
  g.dz_m = 1;
  // grid targets only: their horizons need a post of padding, not the radius
  const PaddedTerrain terrain = pad_terrain(hf, g, 2);
  const double eye = hf.at(vs.observer_i, vs.observer_j) + p.observer_height_m;
  std::vector<float> horizon;
  observer_horizon(terrain, radius, p.exact_rings, hf.spacing_m, p.curvature_coeff, vs.observer_i, vs.observer_j, eye,
                   horizon, true);

  const int side = 2 * radius + 1;
  vs.value.assign(hf.size(), kViewshedOutside);
  for (int j = 0; j < hf.ny; ++j) {
    for (int i = 0; i < hf.nx; ++i) {
      const int dx = i - vs.observer_i, dy = j - vs.observer_j;
      if (std::abs(dx) > radius || std::abs(dy) > radius) continue;
      const double d = std::hypot(double(dx), double(dy)) * hf.spacing_m;
      if (p.max_distance_m > 0 && d > p.max_distance_m) continue;
      const double h = horizon[static_cast<std::size_t>(dy + radius) * static_cast<std::size_t>(side) +
                               static_cast<std::size_t>(dx + radius)];
      const double drop = p.curvature_coeff * d * d / (2.0 * kEarthRadiusM);
      const double target = hf.at(i, j) + p.target_height_m - drop;
      // Rings 0 and 1 have no horizon: always visible.
      const bool visible = h <= kNoHorizon || target > eye + d * h;
      vs.value[static_cast<std::size_t>(j) * static_cast<std::size_t>(hf.nx) + static_cast<std::size_t>(i)] =
          visible ? kViewshedVisible : kViewshedHidden;
    }
  }
  return vs;
}

}  // namespace visvol::fields
