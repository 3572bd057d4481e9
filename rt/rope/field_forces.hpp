// The force field on the rope (paper, equation 1), from one level of detail:
//
//   G = k1 grad F_p + k2 TFF + clearance + hidden-from + visible-to (+ the
//       operator's grasp force, applied to the rope directly)
//
// Accelerations are in m/s^2, scaled so that gains near 1 move a rope across
// the terrain in seconds whatever the terrain: the field gradient is divided
// by a reference gradient of the level (its 90th percentile above the ground,
// saturating at three times that) and everything is multiplied by a reference
// acceleration (spacing / 0.1 s^2).
// k1 < 0 hides, k1 > 0 shows.
//
// Containment: beside the field's volume a push back in.
// Terrain force field: inside the terrain a strong push out along the
// outward displacement; in the band above it (1 - d / offset)^2 along it;
// nothing beyond the band.
// Clearance: within a margin (a fifth of it, at least 1 m) above
// `clearance_m`, a push up ramping to k_c times the saturated visibility pull
// half way down the margin and up to eight times that below, so a hiding rope
// settles above it. It outranks the hidden-from push, which fades out within
// the margin.
// Hidden from / visible to a point: the point's visibility hull (the lowest
// visible height over every column, like a viewshed) is computed once; the
// rope is pushed down where it is above the hull of a point it must stay
// hidden from, up where it is below the hull of a point it must stay visible
// to, ramping in over `hull_margin_m`.
//
// `Level` is a sampler level (DenseLevelView, storage::PackLevel, or the
// executive's resident tiles). acceleration(), visibility() and
// terrain_height_m() are real-time safe; building the hulls is not.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "fields/sampler.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/point_hull.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

struct ForceGains {
  double k1_visibility = -1.0;  // < 0 hides, > 0 shows
  double k2_terrain = 1.0;
  double k_clearance = 1.0;
  double k_hull = 1.0;  // hidden-from and visible-to constraints
  double clearance_m = 30.0;
  double hull_margin_m = 20.0;
  // Ceiling: above min(terrain + max_agl_m, max_altitude_m) a push down as
  // strong as the clearance's push up. Infinite: none.
  double max_agl_m = std::numeric_limits<double>::infinity();
  double max_altitude_m = std::numeric_limits<double>::infinity();
};

// Hulls of each kind (hidden-from, visible-to) the forces hold at most.
inline constexpr int kMaxConstraintHulls = 8;

// `Sampler` answers the queries (fields::FieldSampler<Level>, or one that
// picks the level per query, like storage::ResidentSampler).
template <class Level, class Sampler = fields::FieldSampler<Level>>
class FieldForces final : public RopeEnvironment, public PathField {
 public:
  static constexpr double kSaturation = 3.0;

  FieldForces(const Level& level, const ForceGains& gains) : sampler_(level), gains_(gains) {
    const fields::VolumeGeometry& g = level.geometry();
    accel_ref_ = g.spacing_m / (0.1 * 0.1);
    gradient_ref_ = measure_reference_gradient();
    x0_ = g.origin_x;
    x1_ = g.origin_x + (g.nx - 1) * g.spacing_m;
    y0_ = g.origin_y - (g.ny - 1) * g.spacing_m;
    y1_ = g.origin_y;
    ramp_m_ = g.spacing_m;
    top_m_ = g.top_m();
  }

  void set_gains(const ForceGains& g) { gains_ = g; }
  const ForceGains& gains() const { return gains_; }
  // Pushes the rope back inside `b` (the pack's planning bounds, where F_p
  // counts every observer) instead of the field's extent; the part of `b`
  // beyond the field is ignored.
  void set_bounds(const fields::Bounds2D& b) {
    const fields::VolumeGeometry& g = sampler_.level().geometry();
    x0_ = std::max(b.xmin_m, g.origin_x);
    x1_ = std::min(b.xmax_m, g.origin_x + (g.nx - 1) * g.spacing_m);
    y0_ = std::max(b.ymin_m, g.origin_y - (g.ny - 1) * g.spacing_m);
    y1_ = std::min(b.ymax_m, g.origin_y);
  }
  // At most kMaxHulls of each kind; the hulls must outlive their use.
  static constexpr int kMaxHulls = kMaxConstraintHulls;
  void set_hidden_from(const PointHull* hull) { set_hulls(hidden_, hidden_count_, &hull, hull ? 1 : 0); }
  void set_visible_to(const PointHull* hull) { set_hulls(visible_, visible_count_, &hull, hull ? 1 : 0); }
  // Several of a kind (any beyond kMaxHulls are ignored: callers validate).
  void set_hidden_from(const PointHull* const* hulls, int count) { set_hulls(hidden_, hidden_count_, hulls, count); }
  void set_visible_to(const PointHull* const* hulls, int count) { set_hulls(visible_, visible_count_, hulls, count); }
  const PointHull* hidden_from() const { return hidden_count_ ? hidden_[0] : nullptr; }
  const PointHull* visible_to() const { return visible_count_ ? visible_[0] : nullptr; }
  int hidden_from_count() const { return hidden_count_; }
  int visible_to_count() const { return visible_count_; }
  const PointHull* hidden_from(int k) const {
    return k >= 0 && k < hidden_count_ ? hidden_[static_cast<std::size_t>(k)] : nullptr;
  }
  const PointHull* visible_to(int k) const {
    return k >= 0 && k < visible_count_ ? visible_[static_cast<std::size_t>(k)] : nullptr;
  }
  double reference_acceleration() const { return accel_ref_; }
  double reference_gradient() const { return gradient_ref_; }
  const Sampler& sampler() const { return sampler_; }

  Vec3 acceleration(const Vec3& p) const override {
    const bool with_gradient = gains_.k1_visibility != 0 && gradient_ref_ > 0;
    const bool with_terrain = gains_.k2_terrain != 0;
    // one lookup of the point's cell for the gradient, the terrain force and the height
    const fields::PointSample s = sampler_.sample(p.x(), p.y(), p.z(), with_gradient, with_terrain);
    Vec3 a = Vec3::Zero();
    if (with_gradient) {
      // Saturated at kSaturation reference gradients: F_p changes abruptly at
      // the terrain, and an unbounded pull there would throw the rope through it.
      const Vec3 g = s.gradient_per_m / gradient_ref_;
      const double n = g.norm();
      a += (gains_.k1_visibility * accel_ref_ / std::max(1.0, n / kSaturation)) * g;
    }
    if (with_terrain) a += gains_.k2_terrain * accel_ref_ * terrain_push(s.tff);
    a += accel_ref_ * kSaturation * inward_push(p);
    const double ground = s.height_m;
    const double h = p.z() - ground;
    // Clearance: a push ramping up over a margin above the clearance, as strong
    // as the saturated visibility pull half way down the margin, stronger below.
    const double margin = std::max(0.2 * gains_.clearance_m, 1.0);
    const double depth = gains_.clearance_m + margin - h;
    if (gains_.clearance_m > 0 && depth > 0) {
      a.z() += gains_.k_clearance * accel_ref_ * kSaturation * std::min(2.0 * depth / margin, 8.0);
    }
    // Ceiling: the mirror of the clearance push. The field's top is one too:
    // above it F_p is not known (a console rope flew over a low pack's top).
    const double ceiling = std::min({ground + gains_.max_agl_m, gains_.max_altitude_m, top_m_});
    const double above = h - (ceiling - ground) + margin;
    if (std::isfinite(ceiling) && above > 0) {
      a.z() -= gains_.k_clearance * accel_ref_ * kSaturation * std::min(2.0 * above / margin, 8.0);
    }
    const double hull_margin = std::max(gains_.hull_margin_m, 1e-3);
    double over = 0, under = 0;  // the most binding hull of each kind
    for (int c = 0; c < hidden_count_; ++c)
      over = std::max(over, p.z() - hidden_[static_cast<std::size_t>(c)]->at(p.x(), p.y()) + hull_margin);
    for (int c = 0; c < visible_count_; ++c)
      under = std::max(under, visible_[static_cast<std::size_t>(c)]->at(p.x(), p.y()) + hull_margin - p.z());
    if (over > 0) {
      // Safety first: the push down fades out within the clearance margin.
      const double room = gains_.clearance_m > 0 ? std::clamp((h - gains_.clearance_m) / margin, 0.0, 1.0) : 1.0;
      a.z() -= room * gains_.k_hull * accel_ref_ * kSaturation * std::min(over / hull_margin, 4.0);
    }
    if (under > 0) a.z() += gains_.k_hull * accel_ref_ * kSaturation * std::min(under / hull_margin, 4.0);
    return a;
  }

  double visibility(const Vec3& p) const override { return sampler_.visibility(p.x(), p.y(), p.z()); }
  double terrain_height_m(double x, double y) const override { return sampler_.height(x, y); }

 private:
  // Beside the field's volume the sampler clamps to its edge and the field
  // means nothing there: back in, ramping over one post spacing to eight
  // times the saturated visibility pull (dimensionless). Above its top the
  // top level's F_p and gradient carry on upward, so a path may climb there
  // (to stay visible to a point, say).
  Vec3 inward_push(const Vec3& p) const {
    auto ramp = [&](double excess_m) { return std::min(excess_m / ramp_m_, 8.0); };
    Vec3 push = Vec3::Zero();
    if (p.x() < x0_) push.x() = ramp(x0_ - p.x());
    if (p.x() > x1_) push.x() = -ramp(p.x() - x1_);
    if (p.y() < y0_) push.y() = ramp(y0_ - p.y());
    if (p.y() > y1_) push.y() = -ramp(p.y() - y1_);
    return push;
  }

  // The terrain force field's direction and profile (dimensionless), from
  // the sample at the point.
  Vec3 terrain_push(const fields::TffSample& s) const {
    const double offset = sampler_.level().tff_params().band_offset_m;
    const double d = s.signed_distance_m;
    if (d >= offset) return Vec3::Zero();
    Vec3 e{s.dx_m, s.dy_m, s.dz_m};
    const double len = e.norm();
    e = len > 1e-6 ? Vec3(e / len) : Vec3(Vec3::UnitZ());
    if (d < 0) return (2.0 + std::min(-d / offset, 4.0)) * e;  // inside: out, hard
    const double f = 1.0 - d / offset;
    return f * f * e;
  }

  // The 90th percentile of |grad F_p| over a grid of columns, one to eight
  // levels above the ground: what "a strong gradient" means on this level.
  double measure_reference_gradient() const {
    const fields::VolumeGeometry& g = sampler_.level().geometry();
    std::vector<double> mags;
    const int steps = 16;
    for (int a = 0; a < steps; ++a) {
      for (int b = 0; b < steps; ++b) {
        const double x = g.origin_x + (a + 0.5) / steps * (g.nx - 1) * g.spacing_m;
        const double y = g.origin_y - (b + 0.5) / steps * (g.ny - 1) * g.spacing_m;
        const double ground = sampler_.height(x, y);
        for (double up : {1.5, 3.0, 6.0}) {
          const double m = sampler_.gradient(x, y, ground + up * g.dz_m).norm();
          if (m > 0) mags.push_back(m);
        }
      }
    }
    if (mags.empty()) return 0.0;
    std::nth_element(mags.begin(), mags.begin() + static_cast<std::ptrdiff_t>(mags.size() * 9 / 10), mags.end());
    return mags[mags.size() * 9 / 10];
  }

  Sampler sampler_;
  ForceGains gains_;
  double accel_ref_ = 1.0;
  double gradient_ref_ = 1.0;
  double x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0;  // the field's horizontal extent, world metres
  double ramp_m_ = 1.0;
  double top_m_ = 0;  // the field's top level, m
  static void set_hulls(std::array<const PointHull*, kMaxHulls>& to, int& count, const PointHull* const* from, int n) {
    count = 0;
    for (int c = 0; c < n && count < kMaxHulls; ++c)
      if (from[c]) to[static_cast<std::size_t>(count++)] = from[c];
  }

  std::array<const PointHull*, kMaxHulls> hidden_{}, visible_{};
  int hidden_count_ = 0, visible_count_ = 0;
};

// ---- implementation of the templates ------------------------------------------

}  // namespace visvol::rt
