#include "rt/rope/track_ground.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rt/rope/terrain_probe.hpp"

namespace visvol::rt {

TrackGround::TrackGround(const fields::Heightfield& terrain, const Vec3* v, int count) : terrain_(&terrain) {
  const std::size_t n = count > 0 ? static_cast<std::size_t>(count) : 0;
  track_.assign(v, v + n);
  vertex_m_.assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    track_[k].z() = 0;  // the probes then find where the ground itself is extreme
    if (k == 0) continue;
    const Vec3& a = track_[k - 1];
    const Vec3& b = track_[k];
    const double leg_m = std::hypot(b.x() - a.x(), b.y() - a.y());
    const bool finite = a.allFinite() && b.allFinite() && std::isfinite(leg_m);
    vertex_m_[k] = vertex_m_[k - 1] + (finite ? leg_m : 0.0);
    if (!finite) continue;
    for_each_terrain_probe(terrain, a, b, [&](const Vec3& p, double u) {
      at_m_.push_back(vertex_m_[k - 1] + u * leg_m);
      most_.push_back(fields::bilinear_height(terrain, terrain.i_of(p.x()), terrain.j_of(p.y())));
    });
  }
  const std::size_t leaves = most_.size();
  most_.insert(most_.begin(), leaves, -std::numeric_limits<double>::infinity());
  for (std::size_t i = leaves; i-- > 1;) most_[i] = std::max(most_[2 * i], most_[2 * i + 1]);
}

double TrackGround::ground_at(double along_m) const {
  if (track_.empty()) return -std::numeric_limits<double>::infinity();
  const auto after = std::upper_bound(vertex_m_.begin(), vertex_m_.end(), along_m);
  std::size_t k = static_cast<std::size_t>(after - vertex_m_.begin());
  k = std::clamp<std::size_t>(k, 1, std::max<std::size_t>(track_.size() - 1, 1));
  const Vec3& a = track_[k - 1];
  const Vec3& b = track_.size() > 1 ? track_[k] : track_[0];
  const double leg_m = vertex_m_.size() > 1 ? vertex_m_[k] - vertex_m_[k - 1] : 0.0;
  const double u = leg_m > 0 ? std::clamp((along_m - vertex_m_[k - 1]) / leg_m, 0.0, 1.0) : 0.0;
  const Vec3 p = a + u * (b - a);
  if (!p.allFinite()) return -std::numeric_limits<double>::infinity();
  return fields::bilinear_height(*terrain_, terrain_->i_of(p.x()), terrain_->j_of(p.y()));
}

double TrackGround::highest_breakpoint(std::size_t first, std::size_t end) const {
  double best = -std::numeric_limits<double>::infinity();
  const std::size_t leaves = at_m_.size();
  for (std::size_t lo = first + leaves, hi = end + leaves; lo < hi; lo /= 2, hi /= 2) {
    if (lo % 2 == 1) best = std::max(best, most_[lo++]);
    if (hi % 2 == 1) best = std::max(best, most_[--hi]);
  }
  return best;
}

double TrackGround::highest_m(double from_m, double to_m) const {
  const double to = std::clamp(to_m, 0.0, length_m());
  const double from = std::clamp(std::min(from_m, to), 0.0, to);
  const std::size_t first =
      static_cast<std::size_t>(std::upper_bound(at_m_.begin(), at_m_.end(), from) - at_m_.begin());
  const std::size_t end = static_cast<std::size_t>(std::lower_bound(at_m_.begin(), at_m_.end(), to) - at_m_.begin());
  return std::max({ground_at(from), ground_at(to), highest_breakpoint(first, end)});
}

TrackGround::Stretch TrackGround::held_stretch(int first, int last, double radius_m) const {
  return held_stretch_at(at_vertex_m(first), at_vertex_m(last), radius_m);
}

double TrackGround::held_clearance_m(int first, int last, double first_z_m, double last_z_m, double radius_m) const {
  return held_clearance_at_m(at_vertex_m(first), at_vertex_m(last), first_z_m, last_z_m, radius_m);
}

TrackGround::Stretch TrackGround::held_stretch_at(double first_m, double last_m, double radius_m) const {
  Stretch s;
  s.to_m = std::min(last_m - radius_m, length_m());
  s.from_m = std::max(first_m - radius_m, 0.0);
  return s;
}

double TrackGround::held_clearance_at_m(double first_m, double last_m, double first_z_m, double last_z_m,
                                        double radius_m) const {
  Stretch s = held_stretch_at(first_m, last_m, radius_m);
  // a height that is not a number holds nothing
  if (std::isnan(first_z_m) || std::isnan(last_z_m)) return std::numeric_limits<double>::quiet_NaN();
  const bool descends = last_z_m < first_z_m;
  if (!descends) s.to_m = std::min(s.to_m, first_m);
  if (s.empty()) return std::numeric_limits<double>::infinity();
  return (descends ? last_z_m : first_z_m) - highest_m(s.from_m, s.to_m);
}

}  // namespace visvol::rt
