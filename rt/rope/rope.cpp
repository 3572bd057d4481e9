#include "rt/rope/rope.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>

#include "rt/rope/articulated_rope.hpp"
#include "rt/rope/spring_mass_rope.hpp"

namespace visvol::rt {

const char* to_string(RopeModel model) { return model == RopeModel::spring ? "spring" : "articulated"; }

Result<RopeModel> parse_rope_model(const char* text) {
  if (std::strcmp(text, "spring") == 0) return RopeModel::spring;
  if (std::strcmp(text, "articulated") == 0) return RopeModel::articulated;
  return invalid_argument(std::string("rope model '") + text + "' is not one of spring, articulated");
}

Status validate(const RopeParams& p) {
  std::ostringstream msg;
  auto positive = [&](double v, const char* name) {
    if (!(std::isfinite(v) && v > 0)) {
      msg << "rope: " << name << " " << v << " must be a positive finite number";
      return false;
    }
    return true;
  };
  auto non_negative = [&](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0)) {
      msg << "rope: " << name << " " << v << " must be a finite number >= 0";
      return false;
    }
    return true;
  };
  if (p.max_segments < 2 || p.max_segments > 100000) {
    msg << "rope: capacity " << p.max_segments << " segments is outside 2..100000";
    return invalid_argument(msg.str());
  }
  if (!positive(p.mass_kg, "mass") || !non_negative(p.linear_damping_per_s, "linear damping") ||
      !non_negative(p.angular_damping_per_s, "angular damping") ||
      !non_negative(p.bend_stiffness_n_m_per_rad, "bend stiffness") ||
      !non_negative(p.twist_stiffness_n_m_per_rad, "twist stiffness") ||
      !non_negative(p.joint_damping_n_m_s_per_rad, "joint damping") ||
      !non_negative(p.twist_damping_n_m_s_per_rad, "twist damping") ||
      !positive(p.capsule_radius_m, "capsule radius") ||
      !non_negative(p.stretch_stiffness_n_per_m, "stretch stiffness") ||
      !non_negative(p.stretch_damping_n_s_per_m, "stretch damping") ||
      !non_negative(p.bend_spring_n_per_m, "bending spring") || !positive(p.rest_length_factor, "rest length factor")) {
    return invalid_argument(msg.str());
  }
  if (!(p.verlet_damping >= 0 && p.verlet_damping <= 1)) {
    msg << "rope: Verlet damping " << p.verlet_damping << " is outside [0, 1]";
    return invalid_argument(msg.str());
  }
  if (p.projection_iterations < 0 || p.projection_iterations > 10) {
    msg << "rope: " << p.projection_iterations << " projection iterations is outside 0..10";
    return invalid_argument(msg.str());
  }
  if (!(p.fire_mixing >= 0 && p.fire_mixing <= 1)) {
    msg << "rope: FIRE mixing " << p.fire_mixing << " is outside [0, 1]";
    return invalid_argument(msg.str());
  }
  if (p.fire_mixing > 0 && p.model != RopeModel::articulated) {
    msg << "rope: FIRE mixing applies to the articulated rope only";
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

bool params_valid(const RopeParams& p) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0; };
  return p.max_segments >= 2 && p.max_segments <= 100000 && positive(p.mass_kg) &&
         non_negative(p.linear_damping_per_s) && non_negative(p.angular_damping_per_s) &&
         non_negative(p.bend_stiffness_n_m_per_rad) && non_negative(p.twist_stiffness_n_m_per_rad) &&
         non_negative(p.joint_damping_n_m_s_per_rad) && non_negative(p.twist_damping_n_m_s_per_rad) &&
         positive(p.capsule_radius_m) && non_negative(p.stretch_stiffness_n_per_m) &&
         non_negative(p.stretch_damping_n_s_per_m) && non_negative(p.bend_spring_n_per_m) &&
         positive(p.rest_length_factor) && p.verlet_damping >= 0 && p.verlet_damping <= 1 &&
         p.projection_iterations >= 0 && p.projection_iterations <= 10 && p.fire_mixing >= 0 && p.fire_mixing <= 1 &&
         (!(p.fire_mixing > 0) || p.model == RopeModel::articulated);
}

Result<std::unique_ptr<Rope>> make_rope(const RopeParams& params) {
  VISVOL_RETURN_IF_ERROR(validate(params));
  std::unique_ptr<Rope> rope;
  if (params.model == RopeModel::articulated) {
    rope = std::make_unique<ArticulatedRope>(params);
  } else {
    rope = std::make_unique<SpringMassRope>(params);
  }
  return rope;
}

namespace {

double polyline_length_or_nan(const Vec3* polyline, int points) {
  double total = 0;
  for (int i = 1; i < points; ++i) total += (polyline[i] - polyline[i - 1]).norm();
  return total;  // NaN or infinite when a point is not finite
}

// Calls f(k, point) for the segments + 1 points at equal arc-length spacing
// along a polyline of positive, finite length.
template <class F>
void for_each_resampled(const Vec3* polyline, int points, int segments, F f) {
  const double step = polyline_length_or_nan(polyline, points) / segments;
  f(0, polyline[0]);
  int seg = 0;
  double seg_start = 0;  // arc length at polyline[seg]
  for (int k = 1; k < segments; ++k) {
    const double target = k * step;
    while (seg + 1 < points - 1 && seg_start + (polyline[seg + 1] - polyline[seg]).norm() < target) {
      seg_start += (polyline[seg + 1] - polyline[seg]).norm();
      ++seg;
    }
    const double len = (polyline[seg + 1] - polyline[seg]).norm();
    const double t = len > 0 ? std::clamp((target - seg_start) / len, 0.0, 1.0) : 0.0;
    f(k, Vec3(polyline[seg] + t * (polyline[seg + 1] - polyline[seg])));
  }
  f(segments, polyline[points - 1]);
}

// Length of the chords between the resampled points: zero for a polyline
// that folds back onto itself at the sample points (A, B, A in one segment).
double resampled_length(const Vec3* polyline, int points, int segments) {
  double total = 0;
  Vec3 previous = polyline[0];
  for_each_resampled(polyline, points, segments, [&](int, const Vec3& p) {
    total += (p - previous).norm();
    previous = p;
  });
  return total;
}

}  // namespace

Errc check_polyline(const Vec3* polyline, int points, int segments, int min_segments, int max_segments) {
  if (polyline == nullptr || points < 2 || segments < min_segments || segments > max_segments) {
    return Errc::invalid_argument;
  }
  const double total = polyline_length_or_nan(polyline, points);
  if (!std::isfinite(total) || !polyline[0].allFinite()) return Errc::invalid_argument;
  if (!(total / segments >= kMinSegmentM)) return Errc::invalid_argument;
  return resampled_length(polyline, points, segments) > 0 ? Errc::ok : Errc::invalid_argument;
}

Status describe_polyline(const Vec3* polyline, int points, int segments, int min_segments, int max_segments) {
  if (check_polyline(polyline, points, segments, min_segments, max_segments) == Errc::ok) return Status::ok_status();
  if (segments < min_segments || segments > max_segments) {
    return invalid_argument("rope: " + std::to_string(segments) + " segments is outside " +
                            std::to_string(min_segments) + ".." + std::to_string(max_segments));
  }
  if (polyline == nullptr || points < 2) return invalid_argument("rope: a path needs at least 2 points");
  for (int i = 0; i < points; ++i) {
    if (!polyline[i].allFinite()) return invalid_argument("rope: path point " + std::to_string(i) + " is not finite");
  }
  const double total = polyline_length_or_nan(polyline, points);
  if (!(total > 0)) return invalid_argument("rope: the path has no length");
  if (total / segments >= kMinSegmentM) {
    return invalid_argument("rope: the path folds back onto itself at the " + std::to_string(segments) +
                            " segments' points");
  }
  std::ostringstream s;
  s << "rope: a path of " << total << " m in " << segments << " segments makes them shorter than " << kMinSegmentM
    << " m; use at most " << std::max(0, static_cast<int>(std::floor(total / kMinSegmentM))) << " segments";
  return invalid_argument(s.str());
}

Status resample_polyline(const Vec3* polyline, int points, int segments, Vec3* out) {
  if (points < 2) return invalid_argument("rope: a path needs at least 2 points");
  for (int i = 0; i < points; ++i) {
    if (!polyline[i].allFinite()) {
      return invalid_argument("rope: path point " + std::to_string(i) + " is not finite");
    }
  }
  if (!(polyline_length_or_nan(polyline, points) > 0)) return invalid_argument("rope: the path has no length");
  for_each_resampled(polyline, points, segments, [&](int k, const Vec3& p) { out[k] = p; });
  return Status::ok_status();
}

}  // namespace visvol::rt
