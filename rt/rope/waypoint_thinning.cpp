#include "rt/rope/waypoint_thinning.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "rt/rope/path_metrics.hpp"
#include "rt/rope/track_ground.hpp"

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

namespace {

std::vector<int> every_index(int n) {
  std::vector<int> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  return all;
}

}  // namespace

std::vector<int> thinned_indices(const std::vector<Vec3>& path, const ThinningTolerance& tol,
                                 const std::vector<bool>* kept, const LegTest* leg_holds) {
  const int n = static_cast<int>(path.size());
  if (n <= 2) return every_index(n);
  std::vector<char> keep(static_cast<std::size_t>(n), 0);
  keep.front() = keep.back() = 1;
  // Douglas-Peucker on an explicit stack of spans: a span whose farthest
  // inner vertex is within the tolerance loses them all; else that vertex
  // stays and both halves are thinned. The vertices to keep split the path
  // into spans first.
  std::vector<std::pair<int, int>> spans;
  int from = 0;
  for (int k = 1; k < n; ++k) {
    const std::size_t at = static_cast<std::size_t>(k);
    const bool marked = kept != nullptr && at < kept->size() && (*kept)[at];
    if (k < n - 1 && !marked) continue;
    keep[static_cast<std::size_t>(k)] = 1;
    if (k - from > 1) spans.emplace_back(from, k);
    from = k;
  }
  const double most_work = kMaxThinningWork * n;
  double work = 0;
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    int farthest = -1;
    double worst = 1.0;
    const Vec3& a = path[static_cast<std::size_t>(first)];
    const Vec3& b = path[static_cast<std::size_t>(last)];
    work += last - first - 1;
    if (work > most_work) return every_index(n);  // a contrived path: left as it is
    for (int k = first + 1; k < last; ++k) {
      const double d = thinning_deviation(a, b, path[static_cast<std::size_t>(k)], tol);
      if (d > worst) {
        worst = d;
        farthest = k;
      }
    }
    if (farthest < 0 && leg_holds != nullptr && !(*leg_holds)(first, last)) farthest = first + (last - first) / 2;
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

std::vector<Vec3> thin_waypoints(const std::vector<Vec3>& path, const ThinningTolerance& tol,
                                 const std::vector<bool>* keep, const LegTest* leg_holds) {
  std::vector<Vec3> out;
  for (int i : thinned_indices(path, tol, keep, leg_holds)) out.push_back(path[static_cast<std::size_t>(i)]);
  return out;
}

LegTest held_legs(const std::vector<Vec3>& fitted, const VehicleEnvelope& envelope,
                  const fields::Heightfield& terrain) {
  const double radius_m = switch_distance_m(envelope), hold_m = altitude_hold_m(envelope);
  if (!(radius_m > 0)) return [](int, int) { return true; };
  auto track = std::make_shared<const TrackGround>(terrain, fitted.data(), static_cast<int>(fitted.size()));
  auto v = std::make_shared<const std::vector<Vec3>>(fitted);
  const double needed_m = envelope.clearance_m + kThinnedHeldMarginM;
  return [track, v, needed_m, radius_m, hold_m](int first, int last) {
    const Vec3 &a = (*v)[static_cast<std::size_t>(first)], &b = (*v)[static_cast<std::size_t>(last)];
    // a leg longer than the hold is ramped, not held (track_ground.hpp)
    if (std::hypot(b.x() - a.x(), b.y() - a.y()) > hold_m) return true;
    return track->held_clearance_m(first, last, a.z(), b.z(), radius_m) >= needed_m;
  };
}

std::vector<bool> turns_to_keep(const std::vector<Vec3>& path, double min_turn_radius_m) {
  std::vector<bool> keep(path.size(), false);
  if (!(min_turn_radius_m > 0)) return keep;
  const std::vector<double> room = turn_radii_m(path.data(), static_cast<int>(path.size()));
  for (std::size_t k = 0; k < path.size() && k < room.size(); ++k) {
    keep[k] = room[k] < kTurnKeptFactor * min_turn_radius_m;
  }
  return keep;
}

std::vector<Vec3> thin_for_vehicle(const std::vector<Vec3>& fitted, double min_turn_radius_m,
                                   const ThinningTolerance& tol, const LegTest* leg_holds) {
  const std::vector<bool> turns = turns_to_keep(fitted, min_turn_radius_m);
  return thin_waypoints(fitted, tol, &turns, leg_holds);
}

std::optional<ThinnedPath> thinned_as_good(const std::vector<Vec3>& fitted, const PathCheck& fitted_check,
                                           const PathChecker& checker, Objective objective,
                                           const ThinningTolerance& tol) {
  const LegTest held = held_legs(fitted, checker.spec().envelope, checker.terrain());
  std::vector<Vec3> thinned = thin_for_vehicle(fitted, checker.spec().envelope.min_turn_radius_m, tol, &held);
  if (thinned.size() >= fitted.size()) return std::nullopt;
  PathCheck c = checker.check(thinned);
  const double fc_cost = (objective == Objective::hide ? 1.0 : -1.0) * (c.fc - fitted_check.fc);
  if (meets_less(c, fitted_check) || fc_cost > kThinningFcTie * std::abs(fitted_check.fc)) return std::nullopt;
  return ThinnedPath{std::move(thinned), std::move(c)};
}

}  // namespace visvol::rt
