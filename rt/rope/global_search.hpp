// A global start for the rope: the cheapest path through the voxels of a
// (coarse) level of detail, so the rope refines the best basin rather than the
// nearest local optimum.
//
// Nodes are voxels inside the envelope: at least `clearance_m` above the
// terrain, under the ceiling (terrain + max_agl_m, max_altitude_m, the top
// level) and inside the planning bounds. Edges join a column to its eight
// neighbours, climbing or descending up to the vehicle's limits (at least one
// level, at most kMaxLevelsPerStep); no edge is vertical. An edge costs its
// length times the cost density at its ends plus `length_weight` per metre:
//   hide: density = F_p            (least seen per metre)
//   show: density = F_max - F_p    (most seen per metre; F_max over the level)
// plus `constraint_penalty` per metre of edge in a forbidden volume (above a
// hidden-from hull, below a visible-to hull): a path that keeps every
// constraint is found when the lattice has one, and otherwise the one that
// breaks them over the fewest metres.
// Dijkstra from the voxel nearest the start to the voxel nearest the end.
//
// Offline (allocates O(voxels)); used by the planner, never by the real-time
// thread.
#pragma once

#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <vector>

#include "fields/volume.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

enum class Objective : std::uint8_t { hide = 0, show = 1 };
const char* to_string(Objective objective);

struct GlobalSearchParams {
  static constexpr int kMaxLevelsPerStep = 8;
  Objective objective = Objective::hide;
  double length_weight = 0.0;  // cost per metre on top of the density
  double clearance_m = 30.0;
  double max_agl_m = std::numeric_limits<double>::infinity();
  double max_altitude_m = std::numeric_limits<double>::infinity();
  double max_climb_deg = 90.0;  // 90 (both): vertical edges too, as before limits existed
  double max_descent_deg = 90.0;
  std::optional<fields::Bounds2D> bounds;                 // columns outside are not used
  std::vector<const PointHull*> hidden_from, visible_to;  // hulls on this level
  double constraint_penalty = 100.0;                      // per metre in a forbidden volume (F_p is at most 1)
};

struct GlobalPath {
  std::vector<Vec3> points;  // from, voxel centres, to
  double cost = 0;           // the search's own cost
  std::size_t expanded = 0;  // nodes settled
};

template <class Level>
Result<GlobalPath> global_search(const Level& level, const Vec3& from, const Vec3& to,
                                 const GlobalSearchParams& params) {
  const fields::VolumeGeometry& g = level.geometry();
  const std::size_t nx = static_cast<std::size_t>(g.nx), ny = static_cast<std::size_t>(g.ny);
  const std::size_t count = nx * ny * static_cast<std::size_t>(g.nz);
  // the lowest and highest usable level of every column
  std::vector<int> floor_k(nx * ny), top_k(nx * ny);
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i);
      const double x = g.origin_x + i * g.spacing_m, y = g.origin_y - j * g.spacing_m;
      const double ground = level.post(i, j);
      const double lowest = ground + params.clearance_m;
      const double highest = std::min(ground + params.max_agl_m, params.max_altitude_m);
      floor_k[c] = std::max(0, static_cast<int>(std::ceil((lowest - g.z0_m) / g.dz_m)));
      top_k[c] = std::min(g.nz - 1, static_cast<int>(std::floor(std::min((highest - g.z0_m) / g.dz_m, 1e9))));
      // columns whose cell touches the bounds (the ends snap to their nearest column)
      if (params.bounds) {
        const fields::Bounds2D& b = *params.bounds;
        const double half = 0.5 * g.spacing_m;
        if (x < b.xmin_m - half || x > b.xmax_m + half || y < b.ymin_m - half || y > b.ymax_m + half) top_k[c] = -1;
      }
    }
  }
  double f_max = 0;
  if (params.objective == Objective::show) {
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) f_max = std::max(f_max, static_cast<double>(level.voxel(i, j, k)));
  }
  // forbidden volume: above a hidden-from hull, below a visible-to hull
  auto forbidden = [&](int i, int j, int k) {
    const double x = g.origin_x + i * g.spacing_m, y = g.origin_y - j * g.spacing_m, z = g.z_of(k);
    for (const PointHull* h : params.hidden_from)
      if (z > h->at(x, y)) return true;
    for (const PointHull* h : params.visible_to)
      if (z < h->at(x, y)) return true;
    return false;
  };
  auto index = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * ny + static_cast<std::size_t>(j)) * nx + static_cast<std::size_t>(i);
  };
  // the cost density of every usable voxel, once
  std::vector<float> densities(count, 0.0f);
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i);
      for (int k = floor_k[c]; k <= top_k[c]; ++k) {
        const double f = level.voxel(i, j, k);
        const double penalty = forbidden(i, j, k) ? params.constraint_penalty : 0.0;
        densities[index(i, j, k)] = static_cast<float>((params.objective == Objective::hide ? f : f_max - f) + penalty);
      }
    }
  }
  auto density = [&](int i, int j, int k) { return static_cast<double>(densities[index(i, j, k)]); };
  auto usable = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || i >= g.nx || j >= g.ny) return false;
    const std::size_t c = static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i);
    return k >= floor_k[c] && k <= top_k[c];
  };
  // levels an edge may climb and descend, by its horizontal length
  const bool vertical_edges = params.max_climb_deg >= 90 && params.max_descent_deg >= 90;
  auto levels_for = [&](double deg, double horizontal_m) {
    if (deg >= 90) return GlobalSearchParams::kMaxLevelsPerStep;
    const double levels = std::tan(deg * 0.017453292519943295) * horizontal_m / g.dz_m;
    return std::clamp(static_cast<int>(std::floor(levels)), 1, GlobalSearchParams::kMaxLevelsPerStep);
  };
  const int up_straight = levels_for(params.max_climb_deg, g.spacing_m);
  const int up_diagonal = levels_for(params.max_climb_deg, g.spacing_m * std::sqrt(2.0));
  const int down_straight = levels_for(params.max_descent_deg, g.spacing_m);
  const int down_diagonal = levels_for(params.max_descent_deg, g.spacing_m * std::sqrt(2.0));
  // the usable voxel nearest a point (same column, nearest usable level)
  auto snap = [&](const Vec3& p, int& i, int& j, int& k) {
    i = static_cast<int>(std::lround((p.x() - g.origin_x) / g.spacing_m));
    j = static_cast<int>(std::lround((g.origin_y - p.y()) / g.spacing_m));
    if (i < 0 || j < 0 || i >= g.nx || j >= g.ny) return false;
    const std::size_t c = static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i);
    k = std::clamp(static_cast<int>(std::lround((p.z() - g.z0_m) / g.dz_m)), floor_k[c],
                   std::max(floor_k[c], top_k[c]));
    return usable(i, j, k);
  };
  int si, sj, sk, ti, tj, tk;
  if (!snap(from, si, sj, sk))
    return invalid_argument("global search: the start is outside the level, its planning bounds or its envelope");
  if (!snap(to, ti, tj, tk))
    return invalid_argument("global search: the end is outside the level, its planning bounds or its envelope");

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
    for (int dj = -1; dj <= 1; ++dj) {
      for (int di = -1; di <= 1; ++di) {
        const bool diagonal = di && dj;
        const int up = (di || dj) ? (diagonal ? up_diagonal : up_straight) : (vertical_edges ? 1 : 0);
        const int down = (di || dj) ? (diagonal ? down_diagonal : down_straight) : (vertical_edges ? 1 : 0);
        for (int dk = -down; dk <= up; ++dk) {
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
    return invalid_argument(
        "global search: no path inside the envelope (clearance, ceiling, climb and descent, planning bounds) joins the "
        "start and the end");
  }
  out.cost = dist[goal];
  std::vector<Vec3> reversed;
  for (std::int64_t n = static_cast<std::int64_t>(goal); n >= 0; n = prev[static_cast<std::size_t>(n)]) {
    const std::size_t u = static_cast<std::size_t>(n);
    const int i = static_cast<int>(u % nx), j = static_cast<int>((u / nx) % ny), k = static_cast<int>(u / (nx * ny));
    reversed.push_back({g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, g.z_of(k)});
    if (u == start) break;
  }
  // the ends stand in their own columns: they replace the voxels they snapped to
  out.points.push_back(from);
  for (auto it = reversed.rbegin(); it != reversed.rend(); ++it) {
    const bool end_voxel = it == reversed.rbegin() || it + 1 == reversed.rend();
    if (!end_voxel || reversed.size() < 3) out.points.push_back(*it);
  }
  out.points.push_back(to);
  return out;
}

}  // namespace visvol::rt
