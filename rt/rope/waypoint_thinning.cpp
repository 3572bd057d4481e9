#include "rt/rope/waypoint_thinning.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace visvol::rt {

double thinning_deviation(const Vec3& a, const Vec3& b, const Vec3& p, const ThinningTolerance& tol) {
  // what is not a number is within no tolerance
  if (!a.allFinite() || !b.allFinite() || !p.allFinite()) return std::numeric_limits<double>::infinity();
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const double run2 = dx * dx + dy * dy;
  double across_m = 0, off_m = 0;
  if (run2 > 1e-12) {
    // where p falls along the leg, seen from above
    const double s = std::clamp(((p.x() - a.x()) * dx + (p.y() - a.y()) * dy) / run2, 0.0, 1.0);
    across_m = std::hypot(p.x() - (a.x() + s * dx), p.y() - (a.y() + s * dy));
    off_m = std::abs(p.z() - (a.z() + s * (b.z() - a.z())));
  } else {  // a climb or descent on the spot: p must lie on it
    across_m = std::hypot(p.x() - a.x(), p.y() - a.y());
    off_m = std::max({0.0, p.z() - std::max(a.z(), b.z()), std::min(a.z(), b.z()) - p.z()});
  }
  return std::max(across_m / tol.horizontal_m, off_m / tol.vertical_m);
}

std::vector<int> thinned_indices(const std::vector<Vec3>& path, const ThinningTolerance& tol) {
  const int n = static_cast<int>(path.size());
  if (n <= 2) {
    std::vector<int> all(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) all[static_cast<std::size_t>(i)] = i;
    return all;
  }
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  keep.front() = keep.back() = 1;
  // Douglas-Peucker on an explicit stack of spans: a span whose farthest
  // inner vertex is within the tolerance loses them all; else that vertex
  // stays and both halves are thinned.
  std::vector<std::pair<int, int>> spans{{0, n - 1}};
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    int farthest = -1;
    double worst = 1.0;
    const Vec3& a = path[static_cast<std::size_t>(first)];
    const Vec3& b = path[static_cast<std::size_t>(last)];
    for (int k = first + 1; k < last; ++k) {
      const double d = thinning_deviation(a, b, path[static_cast<std::size_t>(k)], tol);
      if (d > worst) {
        worst = d;
        farthest = k;
      }
    }
    if (farthest < 0) continue;
    keep[static_cast<std::size_t>(farthest)] = 1;
    if (farthest - first > 1) spans.emplace_back(first, farthest);
    if (last - farthest > 1) spans.emplace_back(farthest, last);
  }
  std::vector<int> out;
  for (int i = 0; i < n; ++i)
    if (keep[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

std::vector<Vec3> thin_waypoints(const std::vector<Vec3>& path, const ThinningTolerance& tol) {
  std::vector<Vec3> out;
  for (int i : thinned_indices(path, tol)) out.push_back(path[static_cast<std::size_t>(i)]);
  return out;
}

}  // namespace visvol::rt
