#include "rt/rope/spring_mass_rope.hpp"

#include <algorithm>
#include <cmath>

namespace visvol::rt {

SpringMassRope::SpringMassRope(const RopeParams& params) : p_(params) {
  const std::size_t n = static_cast<std::size_t>(p_.max_segments) + 1;
  // written whole: the capacity's pages touched here, not by the loop (Eigen leaves values unset)
  x_.resize(n, Vec3::Zero());
  x_prev_.resize(n, Vec3::Zero());
  v_.resize(n, Vec3::Zero());
  force_.resize(n, Vec3::Zero());
}

Status SpringMassRope::reset(const Vec3* polyline, int points, int segments) {
  if (check_polyline(polyline, points, segments, 2, p_.max_segments) != Errc::ok) {
    return describe_polyline(polyline, points, segments, 2, p_.max_segments);
  }
  VISVOL_RETURN_IF_ERROR(resample_polyline(polyline, points, segments, x_.data()));
  n_ = segments;
  double total = 0;
  for (int i = 0; i < n_; ++i) total += (x_[static_cast<std::size_t>(i) + 1] - x_[static_cast<std::size_t>(i)]).norm();
  if (!(total > 0)) return invalid_argument("rope: the polyline has no length");
  rest_m_ = p_.rest_length_factor * total / n_;
  bend_rest_m_ = 2.0 * rest_m_;
  for (int i = 0; i <= n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    x_prev_[k] = x_[k];
    v_[k] = Vec3::Zero();
  }
  ends_.start_m = polyline[0];
  ends_.end_m = polyline[points - 1];
  grasp_active_ = false;
  dt_prev_s_ = 0;
  return Status::ok_status();
}

void SpringMassRope::set_ends(const RopeEnds& ends) {
  ends_ = ends;
  pin_ends();
}

void SpringMassRope::pin_ends() {
  if (n_ == 0) return;
  const std::size_t last = static_cast<std::size_t>(n_);
  if (ends_.start_fixed) x_[0] = x_prev_[0] = ends_.start_m, v_[0] = Vec3::Zero();
  if (ends_.end_fixed) x_[last] = x_prev_[last] = ends_.end_m, v_[last] = Vec3::Zero();
}

void SpringMassRope::step(double dt, const RopeEnvironment& env) {
  if (n_ == 0) return;
  const double m = p_.mass_kg;
  for (int i = 0; i <= n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    force_[k] = m * env.acceleration(x_[k]);
  }
  // Spring between particles a and b: stiffness along the spring, damping of
  // the stretch rate.
  auto spring = [&](std::size_t a, std::size_t b, double k_s, double k_v, double rest) {
    const Vec3 d = x_[b] - x_[a];
    const double len = d.norm();
    if (len < 1e-12) return;
    const Vec3 u = d / len;
    const double stretch_rate = (v_[b] - v_[a]).dot(u);
    const Vec3 f = (k_s * (len - rest) + k_v * stretch_rate) * u;
    force_[a] += f;
    force_[b] -= f;
  };
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    spring(k, k + 1, p_.stretch_stiffness_n_per_m, p_.stretch_damping_n_s_per_m, rest_m_);
  }
  for (int i = 0; i + 1 < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    spring(k, k + 2, p_.bend_spring_n_per_m, 0.0, bend_rest_m_);
  }
  if (grasp_active_) {
    const std::size_t g = static_cast<std::size_t>(grasp_segment_);
    force_[g] += (1.0 - grasp_fraction_) * grasp_force_n_;
    force_[g + 1] += grasp_fraction_ * grasp_force_n_;
  }
  // the paper's modified Verlet, plus viscous drag folded into the damping factor
  const double d = std::clamp(p_.verlet_damping + p_.linear_damping_per_s * dt, 0.0, 1.0);
  for (int i = 0; i <= n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3 next = (2.0 - d) * x_[k] - (1.0 - d) * x_prev_[k] + force_[k] * (dt * dt / m);
    x_prev_[k] = x_[k];
    x_[k] = next;
    v_[k] = (x_[k] - x_prev_[k]) / dt;
  }
  dt_prev_s_ = dt;
  pin_ends();
}

double SpringMassRope::kinetic_energy_j() const {
  double e = 0;
  for (int i = 0; i <= n_; ++i) e += 0.5 * p_.mass_kg * v_[static_cast<std::size_t>(i)].squaredNorm();
  return e;
}

double SpringMassRope::length_m() const {
  double len = 0;
  for (int i = 0; i < n_; ++i) len += (x_[static_cast<std::size_t>(i) + 1] - x_[static_cast<std::size_t>(i)]).norm();
  return len;
}

Vec3 SpringMassRope::point(int segment, double fraction) const {
  segment = std::clamp(segment, 0, n_ - 1);
  const std::size_t k = static_cast<std::size_t>(segment);
  return x_[k] + fraction * (x_[k + 1] - x_[k]);
}

Vec3 SpringMassRope::point_velocity(int segment, double fraction) const {
  segment = std::clamp(segment, 0, n_ - 1);
  const std::size_t k = static_cast<std::size_t>(segment);
  return v_[k] + fraction * (v_[k + 1] - v_[k]);
}

void SpringMassRope::set_point_force(int segment, double fraction, const Vec3& force_n) {
  grasp_active_ = true;
  grasp_segment_ = std::clamp(segment, 0, std::max(n_ - 1, 0));
  grasp_fraction_ = std::clamp(fraction, 0.0, 1.0);
  grasp_force_n_ = force_n;
}

bool SpringMassRope::pay_out_at_start() {
  if (n_ == 0 || n_ >= p_.max_segments || ends_.end_fixed) return false;
  // The rope slides along its own path out of the spool (ArticulatedRope's
  // pay-out): the path keeps its shape and the free end moves on along the
  // last segment, by that segment.
  const std::size_t last = static_cast<std::size_t>(n_), next = last + 1;
  const Vec3 on = x_[last] - x_[last - 1];
  x_[next] = x_[last] + on;
  x_prev_[next] = x_prev_[last] + on;
  v_[next] = v_[last];
  ++n_;
  if (grasp_active_) ++grasp_segment_;  // the grasped rope slid on one segment
  return true;
}

}  // namespace visvol::rt
