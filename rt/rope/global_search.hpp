// A global start for the rope: the cheapest path through the voxels of a
// (coarse) level of detail, so the rope refines the best basin rather than the
// nearest local optimum.
//
// Nodes are voxels at least `clearance_m` above the terrain (and at most at
// the top level); edges join the 26 neighbours; an edge costs its length
// times the cost density at its ends plus `length_weight` per metre:
//   hide: density = F_p            (least seen per metre)
//   show: density = F_max - F_p    (most seen per metre; F_max over the level)
// Dijkstra from the voxel nearest the start to the voxel nearest the end.
//
// Offline (allocates O(voxels)); used by the planner, never by the real-time
// thread.
#pragma once

#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <vector>

#include "fields/volume.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

enum class Objective : std::uint8_t { hide = 0, show = 1 };
const char* to_string(Objective objective);

struct GlobalSearchParams {
  Objective objective = Objective::hide;
  double length_weight = 0.0;  // cost per metre on top of the density
  double clearance_m = 30.0;
};

struct GlobalPath {
  std::vector<Vec3> points;   // from, voxel centres, to
  double cost = 0;            // the search's own cost
  std::size_t expanded = 0;   // nodes settled
};

template <class Level>
Result<GlobalPath> global_search(const Level& level, const Vec3& from, const Vec3& to,
                                 const GlobalSearchParams& params) {
  const fields::VolumeGeometry& g = level.geometry();
  const std::size_t nx = static_cast<std::size_t>(g.nx), ny = static_cast<std::size_t>(g.ny);
  const std::size_t count = nx * ny * static_cast<std::size_t>(g.nz);
  // the lowest usable level of every column
  std::vector<int> floor_k(nx * ny);
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const double lowest = level.post(i, j) + params.clearance_m;
      floor_k[static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i)] =
          std::max(0, static_cast<int>(std::ceil((lowest - g.z0_m) / g.dz_m)));
    }
  }
  double f_max = 0;
  if (params.objective == Objective::show) {
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) f_max = std::max(f_max, static_cast<double>(level.voxel(i, j, k)));
  }
  auto density = [&](int i, int j, int k) {
    const double f = level.voxel(i, j, k);
    return params.objective == Objective::hide ? f : f_max - f;
  };
  auto index = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * ny + static_cast<std::size_t>(j)) * nx + static_cast<std::size_t>(i);
  };
  auto usable = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && i < g.nx && j < g.ny && k < g.nz &&
           k >= floor_k[static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i)];
  };
  // the usable voxel nearest a point (same column, nearest usable level)
  auto snap = [&](const Vec3& p, int& i, int& j, int& k) {
    i = static_cast<int>(std::lround((p.x() - g.origin_x) / g.spacing_m));
    j = static_cast<int>(std::lround((g.origin_y - p.y()) / g.spacing_m));
    if (i < 0 || j < 0 || i >= g.nx || j >= g.ny) return false;
    k = std::clamp(static_cast<int>(std::lround((p.z() - g.z0_m) / g.dz_m)),
                   floor_k[static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i)], g.nz - 1);
    return usable(i, j, k);
  };
  int si, sj, sk, ti, tj, tk;
  if (!snap(from, si, sj, sk)) return invalid_argument("global search: the start is outside the level or above its top");
  if (!snap(to, ti, tj, tk)) return invalid_argument("global search: the end is outside the level or above its top");

  std::vector<float> dist(count, std::numeric_limits<float>::infinity());
  std::vector<std::int32_t> prev(count, -1);
  using Item = std::pair<float, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  const std::size_t start = index(si, sj, sk), goal = index(ti, tj, tk);
  dist[start] = 0;
  open.push({0.0f, start});
  GlobalPath out;
  while (!open.empty()) {
    const auto [d, node] = open.top();
    open.pop();
    if (d > dist[node]) continue;
    ++out.expanded;
    if (node == goal) break;
    const int i = static_cast<int>(node % nx), j = static_cast<int>((node / nx) % ny),
              k = static_cast<int>(node / (nx * ny));
    const double here = density(i, j, k);
    for (int dk = -1; dk <= 1; ++dk) {
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          if (!di && !dj && !dk) continue;
          const int a = i + di, b = j + dj, c = k + dk;
          if (c < 0 || !usable(a, b, c)) continue;
          const double len = std::sqrt((di * di + dj * dj) * g.spacing_m * g.spacing_m + dk * dk * g.dz_m * g.dz_m);
          const double cost = len * (0.5 * (here + density(a, b, c)) + params.length_weight);
          const std::size_t next = index(a, b, c);
          const float nd = static_cast<float>(d + cost);
          if (nd < dist[next]) {
            dist[next] = nd;
            prev[next] = static_cast<std::int32_t>(node);
            open.push({nd, next});
          }
        }
      }
    }
  }
  if (!std::isfinite(dist[goal])) {
    return invalid_argument("global search: no path keeps the clearance between the start and the end");
  }
  out.cost = dist[goal];
  std::vector<Vec3> reversed;
  for (std::int64_t n = static_cast<std::int64_t>(goal); n >= 0; n = prev[static_cast<std::size_t>(n)]) {
    const std::size_t u = static_cast<std::size_t>(n);
    const int i = static_cast<int>(u % nx), j = static_cast<int>((u / nx) % ny), k = static_cast<int>(u / (nx * ny));
    reversed.push_back({g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, g.z_of(k)});
    if (u == start) break;
  }
  out.points.push_back(from);
  for (auto it = reversed.rbegin(); it != reversed.rend(); ++it) out.points.push_back(*it);
  out.points.push_back(to);
  return out;
}

}  // namespace visvol::rt
