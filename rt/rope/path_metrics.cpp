#include "rt/rope/path_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace visvol::rt {

namespace {

constexpr double kDegPerRad = 57.29577951308232;

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

double path_fc(const Vec3* vertices, int count, const PathField& field, int samples,
               Importance importance) {
  if (count < 2 || samples < 2) return 0.0;
  const double total = polyline_length(vertices, count);
  if (!(total > 0)) return field.visibility(vertices[0]) * (importance ? importance(0.0) : 1.0);
  double sum = 0;
  walk(vertices, count, samples, total, [&](const Vec3& p, double t) {
    sum += field.visibility(p) * (importance ? importance(t) : 1.0);
  });
  return sum / samples;
}

PathMetrics path_metrics(const Vec3* v, int count, const PathField& field, int samples,
                         double clearance_step_m, Importance importance) {
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
  for (int i = 1; i + 1 < count; ++i) {
    // radius of the circle through three points: abc / (4 * area)
    const double a = (v[i] - v[i - 1]).norm(), b = (v[i + 1] - v[i]).norm(), c = (v[i + 1] - v[i - 1]).norm();
    const double area2 = (v[i] - v[i - 1]).cross(v[i + 1] - v[i - 1]).norm();  // twice the area
    if (area2 < 1e-12) continue;  // straight
    m.min_turn_radius_m = std::min(m.min_turn_radius_m, a * b * c / (2.0 * area2));
  }
  return m;
}

}  // namespace visvol::rt
