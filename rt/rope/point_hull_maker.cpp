#include "rt/rope/point_hull_maker.hpp"

#include "rt/rope/path_check.hpp"

#include <cmath>
#include <string>

namespace visvol::rt {

Result<PointHull> PointHullMaker::operator()(const Vec3& p, const char* name) const {
  int pi = 0, pj = 0;
  if (!p.allFinite() || !hull_post(g_, p, pi, pj)) {
    return invalid_argument(std::string(name) + ": point is outside the pack");
  }
  VISVOL_RETURN_IF_ERROR(check_observer_altitude(name, p.z()));
  if (p.z() < hf_.at(pi, pj)) {
    return invalid_argument(std::string(name) + ": point is " + std::to_string(hf_.at(pi, pj) - p.z()) +
                            " m below the terrain");
  }
  const int radius = std::max(g_.nx, g_.ny) - 1;
  if (radius > fields::kMaxHullRing) {
    return invalid_argument(std::string(name) + ": the level is " + std::to_string(radius + 1) +
                            " posts across, over the " + std::to_string(fields::kMaxHullRing + 1) +
                            " an observer's hull reaches");
  }
  std::vector<float> horizon;
  fields::observer_horizon(padded_, radius, 64, g_.spacing_m, 0.0, pi, pj, p.z(), horizon, true);
  PointHull hull;
  hull.nx = g_.nx;
  hull.ny = g_.ny;
  hull.origin_x = g_.origin_x;
  hull.origin_y = g_.origin_y;
  hull.spacing_m = g_.spacing_m;
  hull.height_m.assign(hf_.height_m.size(), 0.0f);
  const std::size_t side = 2 * static_cast<std::size_t>(radius) + 1;
  for (int j = 0; j < g_.ny; ++j) {
    for (int i = 0; i < g_.nx; ++i) {
      const double h =
          horizon[static_cast<std::size_t>(j - pj + radius) * side + static_cast<std::size_t>(i - pi + radius)];
      const double d = std::hypot(double(i - pi), double(j - pj)) * g_.spacing_m;
      const double ground = hf_.at(i, j);
      const double lowest = h <= fields::kNoHorizon ? ground : std::max(ground, p.z() + d * h);
      hull.height_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(g_.nx) + static_cast<std::size_t>(i)] =
          static_cast<float>(lowest);
    }
  }
  return hull;
}

std::size_t PointHullMaker::bytes(int nx, int ny) {
  return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * sizeof(float) +
         fields::padded_terrain_bytes(nx, ny, 2);
}

}  // namespace visvol::rt
