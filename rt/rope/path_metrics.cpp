#include "rt/rope/path_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/angles.hpp"

namespace visvol::rt {

namespace {

double polyline_length(const Vec3* v, int count) {
  double total = 0;
  for (int i = 1; i < count; ++i) total += (v[i] - v[i - 1]).norm();
  return total;
}

// Calls fn(point, t) at `samples` points evenly spaced by arc length (t in [0, 1]).
template <typename Fn>
void walk(const Vec3* v, int count, int samples, double total, Fn&& fn) {
  int seg = 0;
  double seg_start = 0;
  for (int s = 0; s < samples; ++s) {
    const double t = samples > 1 ? static_cast<double>(s) / (samples - 1) : 0.0;
    const double target = t * total;
    while (seg + 1 < count - 1 && seg_start + (v[seg + 1] - v[seg]).norm() < target) {
      seg_start += (v[seg + 1] - v[seg]).norm();
      ++seg;
    }
    const double len = (v[seg + 1] - v[seg]).norm();
    const double f = len > 0 ? std::clamp((target - seg_start) / len, 0.0, 1.0) : 0.0;
    fn(Vec3(v[seg] + f * (v[seg + 1] - v[seg])), t);
  }
}

}  // namespace

double path_fc(const Vec3* vertices, int count, const PathField& field, int samples, Importance importance) {
  if (count < 2 || samples < 2) return 0.0;
  const double total = polyline_length(vertices, count);
  if (!(total > 0)) return field.visibility(vertices[0]) * (importance ? importance(0.0) : 1.0);
  double sum = 0;
  walk(vertices, count, samples, total,
       [&](const Vec3& p, double t) { sum += field.visibility(p) * (importance ? importance(t) : 1.0); });
  return sum / samples;
}

PathMetrics path_metrics(const Vec3* v, int count, const PathField& field, int samples, double clearance_step_m,
                         Importance importance) {
  PathMetrics m;
  if (count < 2) return m;
  m.length_m = polyline_length(v, count);
  m.fc = path_fc(v, count, field, samples, importance);
  const int clearance_samples =
      std::max(2, static_cast<int>(std::ceil(m.length_m / std::max(clearance_step_m, 1e-3))) + 1);
  m.min_clearance_m = std::numeric_limits<double>::infinity();
  walk(v, count, clearance_samples, m.length_m, [&](const Vec3& p, double) {
    m.min_clearance_m = std::min(m.min_clearance_m, p.z() - field.terrain_height_m(p.x(), p.y()));
  });
  for (int i = 1; i < count; ++i) {
    const Vec3 d = v[i] - v[i - 1];
    const double horizontal = std::hypot(d.x(), d.y());
    if (d.norm() < 1e-9) continue;
    const double angle = std::atan2(d.z(), horizontal) * kDegPerRad;
    m.max_climb_deg = std::max(m.max_climb_deg, angle);
    m.max_descent_deg = std::max(m.max_descent_deg, -angle);
  }
  m.min_turn_radius_m = std::numeric_limits<double>::infinity();
  for (double r : turn_radii_m(v, count)) m.min_turn_radius_m = std::min(m.min_turn_radius_m, r);
  return m;
}

std::vector<double> turn_radii_m(const Vec3* v, int count) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::size_t n = count > 0 ? static_cast<std::size_t>(count) : 0;
  std::vector<double> radius(n, inf);
  // The horizontal track: each run of vertices within kSameSpotM of the run's
  // first is one spot (a repeated waypoint, a climb on the spot), so the turn
  // there is judged between the segments either side of the run.
  std::vector<std::size_t> spot_first(n), spot_of(n);
  std::size_t spots = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (spots == 0 || !same_spot(v[i], v[spot_first[spots - 1]])) spot_first[spots++] = i;
    spot_of[i] = spots - 1;
  }
  auto xy = [&](std::size_t s) { return Eigen::Vector2d(v[spot_first[s]].x(), v[spot_first[s]].y()); };
  // t = tan(turn / 2) at each interior spot
  std::vector<double> t(spots, 0.0), spot_radius(spots, inf);
  for (std::size_t s = 1; s + 1 < spots; ++s) {
    const Eigen::Vector2d u = xy(s) - xy(s - 1), w = xy(s + 1) - xy(s);
    const double turn = std::acos(std::clamp(u.dot(w) / (u.norm() * w.norm()), -1.0, 1.0));
    t[s] = turn > 1e-9 ? std::tan(0.5 * std::min(turn, M_PI - 1e-9)) : 0.0;
  }
  for (std::size_t s = 0; s + 1 < spots; ++s) {
    const double tangents = t[s] + t[s + 1];
    if (tangents <= 0) continue;
    const double bound = (xy(s + 1) - xy(s)).norm() / tangents;
    if (t[s] > 0) spot_radius[s] = std::min(spot_radius[s], bound);
    if (t[s + 1] > 0) spot_radius[s + 1] = std::min(spot_radius[s + 1], bound);
  }
  // the path's ends are never turns, even where a run joins them
  for (std::size_t i = 1; i + 1 < n; ++i) radius[i] = spot_radius[spot_of[i]];
  return radius;
}

}  // namespace visvol::rt
