#include "rt/rope/articulated_rope.hpp"

#include <algorithm>
#include <cmath>

namespace visvol::rt {

namespace {

// The rotation vector of a unit quaternion, angle in [0, pi].
Vec3 log_map(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Vec3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2.0 * v;
  return v * (2.0 * std::atan2(s, q.w()) / s);
}

}  // namespace

namespace detail {

// The unit quaternion of rotation vector w (its exponential map). A step
// turns a capsule by milliradians: there the series of cos(a/2) and
// sin(a/2)/a, whose next terms are below 1e-19, replaces sin and cos (about
// 400 calls a step).
Eigen::Quaterniond exp_map(const Vec3& w) {
  const double a2 = w.squaredNorm();
  if (a2 < 1e-6) {
    const double c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0;    // cos(a / 2)
    const double s = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0;  // sin(a / 2) / a
    return Eigen::Quaterniond(c, s * w.x(), s * w.y(), s * w.z());
  }
  const double angle = std::sqrt(a2);
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

// The shortest rotation taking body z onto DIR (not zero): Eigen's
// FromTwoVectors with its one case written out. Eigen finds the axis of a
// half turn with a JacobiSVD, whose instantiation was most of this file's
// compile time (alone: 25 s -> 10 s at -O3, 57 s -> 23 s under clang's
// ASan+UBSan). Straight down, any axis across z turns z onto it; x is taken
// (the twist the joint springs then see between such a capsule and its
// neighbours follows from that choice, as it did from Eigen's).
Eigen::Quaterniond from_body_z(const Vec3& dir) {
  const Vec3 d = dir.normalized();
  const double c = d.z();                                // cos of the angle between z and dir
  const double across2 = d.x() * d.x() + d.y() * d.y();  // sin^2 of that angle
  // 1 + c, from 1 - c^2 = sin^2 where dir points nearly down (1 + c would
  // cancel there; elsewhere Eigen's sums, to the bit)
  const double one_plus_c = c >= -0.9 ? 1.0 + c : across2 / (1.0 - c);
  if (!(one_plus_c > 0)) return Eigen::Quaterniond(0.0, 1.0, 0.0, 0.0);  // straight down: a half turn about x
  const double s = std::sqrt(one_plus_c * 2.0);                          // |(1 + c, z x d)|
  const double inv_s = 1.0 / s;
  return Eigen::Quaterniond(s * 0.5, -d.y() * inv_s, d.x() * inv_s, 0.0);
}

// Column j of [r]x m is r x m.col(j).
Eigen::Matrix3d cross_times(const Vec3& r, const Eigen::Matrix3d& m) {
  Eigen::Matrix3d out;
  for (int j = 0; j < 3; ++j) out.col(j) = r.cross(m.col(j));
  return out;
}

// Row i of m [r]x is m.row(i) x r.
Eigen::Matrix3d times_cross(const Eigen::Matrix3d& m, const Vec3& r) {
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) out.row(i) = m.row(i).cross(r.transpose());
  return out;
}

}  // namespace detail

// Every buffer written whole here (Eigen's types leave their values unset):
// the pages of the whole capacity are touched at construction, not by the
// 1 kHz loop the first time a rope grows (spool mode) into them.
ArticulatedRope::ArticulatedRope(const RopeParams& params) : p_(params) {
  const std::size_t n = static_cast<std::size_t>(p_.max_segments);
  const Vec3 zero = Vec3::Zero();
  x_.resize(n, zero);
  v_.resize(n, zero);
  w_.resize(n, zero);
  force_.resize(n, zero);
  torque_.resize(n, zero);
  q_.resize(n, Eigen::Quaterniond::Identity());
  axis_.resize(n, Vec3::UnitZ());
  inv_inertia_.resize(n, Eigen::Matrix3d::Zero());
  sample_acc_.resize(2 * n + 1, zero);
  joints_.resize(n + 1, Joint{{-1, zero, 1.0}, {-1, zero, 1.0}, zero});
  d_inv_.resize(n + 1, Eigen::Matrix3d::Zero());
  upper_.resize(n + 1, Eigen::Matrix3d::Zero());
  lower_.resize(n + 1, Eigen::Matrix3d::Zero());
  rhs_.resize(n + 1, zero);
  lambda_.resize(n + 1, zero);
  vertices_.resize(n + 1, zero);
}

Status ArticulatedRope::reset(const Vec3* polyline, int points, int segments) {
  if (check_polyline(polyline, points, segments, 1, p_.max_segments) != Errc::ok) {
    return describe_polyline(polyline, points, segments, 1, p_.max_segments);
  }
  VISVOL_RETURN_IF_ERROR(resample_polyline(polyline, points, segments, vertices_.data()));
  n_ = segments;
  double total = 0;
  for (int i = 0; i < n_; ++i)
    total += (vertices_[static_cast<std::size_t>(i) + 1] - vertices_[static_cast<std::size_t>(i)]).norm();
  half_m_ = 0.5 * total / n_;
  if (!(half_m_ > 0)) return invalid_argument("rope: the polyline has no length");
  const double len = 2 * half_m_, r = p_.capsule_radius_m, m = p_.mass_kg;
  // A solid cylinder along body z.
  inertia_body_ = {m * (3 * r * r + len * len) / 12.0, m * (3 * r * r + len * len) / 12.0, m * r * r / 2.0};
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3 a = vertices_[k], b = vertices_[k + 1];
    x_[k] = 0.5 * (a + b);
    const Vec3 dir = b - a;
    q_[k] = dir.norm() > 0 ? detail::from_body_z(dir) : Eigen::Quaterniond::Identity();
    v_[k] = w_[k] = Vec3::Zero();
  }
  refresh_axes();
  ends_.start_m = polyline[0];
  ends_.end_m = polyline[points - 1];
  grasp_active_ = false;
  fire_share_ = p_.fire_mixing;
  fire_downhill_steps_ = 0;
  // Equal capsules on a bent polyline leave small gaps: close them.
  for (int it = 0; it < 6; ++it) {
    build_joints();
    if (joint_count_ == 0) break;
    factor_chain();
    for (int k = 0; k < joint_count_; ++k)
      rhs_[static_cast<std::size_t>(k)] = -joint_error(joints_[static_cast<std::size_t>(k)]);
    solve_chain();
    apply_impulses(true);
  }
  update_vertices();
  return Status::ok_status();
}

void ArticulatedRope::refresh_axes() {
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    axis_[k] = q_[k] * Vec3::UnitZ();
  }
}

Eigen::Matrix3d ArticulatedRope::inverse_inertia_world(int i) const {
  const Eigen::Matrix3d r = q_[static_cast<std::size_t>(i)].toRotationMatrix();
  return r * inertia_body_.cwiseInverse().asDiagonal() * r.transpose();
}

Vec3 ArticulatedRope::attachment_point(const Attachment& at, const Vec3& anchor) const {
  return at.body < 0 ? anchor : x_[static_cast<std::size_t>(at.body)] + at.r;
}

Vec3 ArticulatedRope::joint_error(const Joint& j) const {
  return attachment_point(j.a, j.anchor) - attachment_point(j.b, j.anchor);
}

Vec3 ArticulatedRope::joint_velocity(const Joint& j) const {
  auto vel = [&](const Attachment& at) {
    if (at.body < 0) return Vec3(Vec3::Zero());
    const std::size_t b = static_cast<std::size_t>(at.body);
    return Vec3(v_[b] + w_[b].cross(at.r));
  };
  return vel(j.a) - vel(j.b);
}

void ArticulatedRope::refresh_attachments() {
  for (int k = 0; k < joint_count_; ++k) {
    Joint& j = joints_[static_cast<std::size_t>(k)];
    for (Attachment* at : {&j.a, &j.b}) {
      if (at->body < 0) continue;
      // The a side of a joint is a capsule's end b, the b side a capsule's end a
      // (the start anchor's a side is capsule 0's end a).
      const bool at_end_b = (at == &j.a) && !(ends_.start_fixed && k == 0);
      const Vec3 end = at_end_b ? end_b(at->body) : end_a(at->body);
      at->r = end - x_[static_cast<std::size_t>(at->body)];
    }
  }
}

void ArticulatedRope::build_joints() {
  int k = 0;
  auto at = [&](int body, const Vec3& point, double sign) {
    return Attachment{body, point - x_[static_cast<std::size_t>(body)], sign};
  };
  if (ends_.start_fixed)
    joints_[static_cast<std::size_t>(k++)] =
        Joint{at(0, end_a(0), 1.0), Attachment{-1, Vec3::Zero(), -1.0}, ends_.start_m};
  for (int i = 0; i + 1 < n_; ++i) {
    joints_[static_cast<std::size_t>(k++)] = Joint{at(i, end_b(i), 1.0), at(i + 1, end_a(i + 1), -1.0), Vec3::Zero()};
  }
  if (ends_.end_fixed) {
    joints_[static_cast<std::size_t>(k++)] =
        Joint{at(n_ - 1, end_b(n_ - 1), 1.0), Attachment{-1, Vec3::Zero(), -1.0}, ends_.end_m};
  }
  joint_count_ = k;
  for (int i = 0; i < n_; ++i) inv_inertia_[static_cast<std::size_t>(i)] = inverse_inertia_world(i);
}

void ArticulatedRope::factor_chain() {
  const double inv_m = 1.0 / p_.mass_kg;
  // [r_s]x I^-1 for an attachment: the left half of its couplings, shared by
  // the diagonal block and the off-diagonal one that involve it.
  auto left_of = [&](const Attachment& s) {
    return detail::cross_times(s.r, inv_inertia_[static_cast<std::size_t>(s.body)]);
  };
  // K(r1, r2) for two attachments on one body: s1 s2 (I/m - [r1]x I^-1 [r2]x).
  auto coupling = [&](const Eigen::Matrix3d& left, const Attachment& s, const Attachment& t) {
    return Eigen::Matrix3d(s.sign * t.sign * (inv_m * Eigen::Matrix3d::Identity() - detail::times_cross(left, t.r)));
  };
  // block LDU: d_inv_ holds the pivots' inverses, lower_ the multipliers
  for (int k = 0; k < joint_count_; ++k) {
    const std::size_t kk = static_cast<std::size_t>(k);
    const Joint& j = joints_[kk];
    Eigen::Matrix3d d = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d left_a = Eigen::Matrix3d::Zero(), left_b = Eigen::Matrix3d::Zero();  // unused for an anchor
    if (j.a.body >= 0) {
      left_a = left_of(j.a);
      d += coupling(left_a, j.a, j.a);
    }
    if (j.b.body >= 0) {
      left_b = left_of(j.b);
      d += coupling(left_b, j.b, j.b);
    }
    if (k > 0) {
      lower_[kk] = upper_[kk - 1].transpose() * d_inv_[kk - 1];  // A(k, k-1) D(k-1)^-1
      d -= lower_[kk] * upper_[kk - 1];
    }
    d_inv_[kk] = d.inverse();
    // Joints k and k + 1 share one body: the b side of k is the a side of k + 1
    // (the start anchor's joint shares its a side, body 0).
    upper_[kk] = Eigen::Matrix3d::Zero();
    if (k + 1 < joint_count_) {
      const Attachment& next_a = joints_[kk + 1].a;
      if (j.b.body >= 0 && j.b.body == next_a.body) {
        upper_[kk] = coupling(left_b, j.b, next_a);
      } else if (j.a.body >= 0 && j.a.body == next_a.body) {
        upper_[kk] = coupling(left_a, j.a, next_a);
      }
    }
  }
}

void ArticulatedRope::solve_chain() {
  for (int k = 1; k < joint_count_; ++k) {
    const std::size_t kk = static_cast<std::size_t>(k);
    rhs_[kk] -= lower_[kk] * rhs_[kk - 1];
  }
  for (int k = joint_count_ - 1; k >= 0; --k) {
    const std::size_t kk = static_cast<std::size_t>(k);
    Vec3 y = rhs_[kk];
    if (k + 1 < joint_count_) y -= upper_[kk] * lambda_[kk + 1];
    lambda_[kk] = d_inv_[kk] * y;
  }
}

void ArticulatedRope::apply_impulses(bool positions) {
  const double inv_m = 1.0 / p_.mass_kg;
  for (int k = 0; k < joint_count_; ++k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    const Vec3& l = lambda_[static_cast<std::size_t>(k)];
    for (const Attachment* at : {&j.a, &j.b}) {
      if (at->body < 0) continue;
      const std::size_t b = static_cast<std::size_t>(at->body);
      const Vec3 impulse = at->sign * l;
      const Vec3 spin = inv_inertia_[b] * at->r.cross(impulse);
      if (positions) {
        x_[b] += inv_m * impulse;
        q_[b] = (detail::exp_map(spin) * q_[b]).normalized();
      } else {
        v_[b] += inv_m * impulse;
        w_[b] += spin;
      }
    }
  }
  if (positions) refresh_axes();
}

void ArticulatedRope::accumulate_forces(const RopeEnvironment& env) {
  // the field at the capsule ends and middles (ends are shared)
  for (int i = 0; i < n_; ++i) {
    sample_acc_[2 * static_cast<std::size_t>(i)] = env.acceleration(end_a(i));
    sample_acc_[2 * static_cast<std::size_t>(i) + 1] = env.acceleration(x_[static_cast<std::size_t>(i)]);
  }
  sample_acc_[2 * static_cast<std::size_t>(n_)] = env.acceleration(end_b(n_ - 1));
  const double m = p_.mass_kg;
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3& acc_a = sample_acc_[2 * k];
    const Vec3& acc_m = sample_acc_[2 * k + 1];
    const Vec3& acc_b = sample_acc_[2 * k + 2];
    // Simpson's rule: the average over the capsule and the moment about its centre.
    force_[k] = m * (acc_a + 4.0 * acc_m + acc_b) / 6.0;
    torque_[k] = m * half_m_ / 6.0 * axis(i).cross(acc_b - acc_a);
  }
  if (grasp_active_) {
    const std::size_t g = static_cast<std::size_t>(grasp_segment_);
    const Vec3 p = point(grasp_segment_, grasp_fraction_);
    force_[g] += grasp_force_n_;
    torque_[g] += (p - x_[g]).cross(grasp_force_n_);
  }
}

void ArticulatedRope::add_joint_springs() {
  for (int i = 0; i + 1 < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    // relative rotation of capsule i + 1 seen from capsule i
    const Vec3 theta = log_map(q_[k].conjugate() * q_[k + 1]);
    const Vec3 twist = theta.z() * Vec3::UnitZ();
    const Vec3 swing = theta - twist;
    const Vec3 spring = q_[k] * (-(p_.bend_stiffness_n_m_per_rad * swing + p_.twist_stiffness_n_m_per_rad * twist));
    // Damping of the relative spin, split like the springs: the axial inertia
    // is far smaller than the bending one and needs its own, smaller, damping.
    const Vec3 rel = w_[k + 1] - w_[k];
    const Vec3 ax = axis(i);
    const Vec3 rel_twist = rel.dot(ax) * ax;
    const Vec3 damping =
        -p_.joint_damping_n_m_s_per_rad * (rel - rel_twist) - p_.twist_damping_n_m_s_per_rad * rel_twist;
    torque_[k + 1] += spring + damping;
    torque_[k] -= spring + damping;
  }
}

void ArticulatedRope::step(double dt, const RopeEnvironment& env) {
  if (n_ == 0) return;
  accumulate_forces(env);
  add_joint_springs();
  // velocities: semi-implicit Euler with implicit viscous damping
  const double lin = 1.0 / (1.0 + p_.linear_damping_per_s * dt);
  const double ang = 1.0 / (1.0 + p_.angular_damping_per_s * dt);
  build_joints();
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    v_[k] = (v_[k] + dt / p_.mass_kg * force_[k]) * lin;
    w_[k] = (w_[k] + dt * (inv_inertia_[k] * torque_[k])) * ang;
  }
  if (joint_count_ > 0) {
    factor_chain();  // reused by the projections below: the configuration barely moves in a step
    solve_joint_velocities(dt);
  }
  if (p_.fire_mixing > 0) fire_adjust_velocities(dt);
  // positions and orientations
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    x_[k] += dt * v_[k];
    q_[k] = (detail::exp_map(dt * w_[k]) * q_[k]).normalized();
  }
  refresh_axes();
  // project away what the linearisation left open (with this step's factors)
  for (int it = 0; it < p_.projection_iterations && joint_count_ > 0; ++it) {
    refresh_attachments();
    for (int k = 0; k < joint_count_; ++k)
      rhs_[static_cast<std::size_t>(k)] = -joint_error(joints_[static_cast<std::size_t>(k)]);
    solve_chain();
    apply_impulses(true);
  }
  update_vertices();
}

// Joint impulses (with this step's factors): relative velocity at every joint
// to -beta * gap / dt.
void ArticulatedRope::solve_joint_velocities(double dt_s) {
  constexpr double kBaumgarte = 0.2;
  for (int k = 0; k < joint_count_; ++k) {
    const Joint& j = joints_[static_cast<std::size_t>(k)];
    rhs_[static_cast<std::size_t>(k)] = -joint_velocity(j) - (kBaumgarte / dt_s) * joint_error(j);
  }
  solve_chain();
  apply_impulses(false);
}

void ArticulatedRope::fire_adjust_velocities(double dt_s) {
  double power_w = 0, speed2_m2_per_s2 = 0, force2_n2 = 0;
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    power_w += force_[k].dot(v_[k]) + torque_[k].dot(w_[k]);
    speed2_m2_per_s2 += v_[k].squaredNorm();
    force2_n2 += force_[k].squaredNorm();
  }
  // A state that stopped being finite is left as it is: zeroed, it would
  // look at rest and hide the divergence from whoever watches the energy.
  if (!std::isfinite(power_w)) return;
  if (power_w <= 0) {  // uphill (or still): stop, and start mixing afresh
    for (int i = 0; i < n_; ++i) {
      v_[static_cast<std::size_t>(i)].setZero();
      w_[static_cast<std::size_t>(i)].setZero();
    }
    fire_share_ = p_.fire_mixing;
    fire_downhill_steps_ = 0;
    return;
  }
  const double to_speed_s_per_kg = force2_n2 > 0 ? std::sqrt(speed2_m2_per_s2 / force2_n2) : 0.0;  // |v| / |F|
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    v_[k] = (1 - fire_share_) * v_[k] + fire_share_ * to_speed_s_per_kg * force_[k];
  }
  // The turned velocities pull on the joints: solved again, so the positions
  // move with velocities the joints allow.
  if (joint_count_ > 0) solve_joint_velocities(dt_s);
  // FIRE's constants, per step as its authors give them (five steps
  // downhill, then 1% less a step): the step changes the share's decay in
  // simulated time. Tried per simulated second (stop 31, the same at the
  // planner's 4 ms): Taunus's plans, whose step is shorter, settled in 19.9
  // and 12.8 s instead of 8.1 and 10.6.
  constexpr int kDownhillSteps = 5;
  constexpr double kShareDecay = 0.99;
  if (++fire_downhill_steps_ > kDownhillSteps) fire_share_ *= kShareDecay;
}

// A vertex is the middle of the joint between two capsules; a fixed end is
// its anchor exactly, so the path starts and ends where the operator said
// (the joint solver leaves a gap of under 1e-4 of a segment there).
void ArticulatedRope::update_vertices() {
  vertices_[0] = ends_.start_fixed ? ends_.start_m : end_a(0);
  for (int i = 1; i < n_; ++i) vertices_[static_cast<std::size_t>(i)] = 0.5 * (end_b(i - 1) + end_a(i));
  vertices_[static_cast<std::size_t>(n_)] = ends_.end_fixed ? ends_.end_m : end_b(n_ - 1);
}

double ArticulatedRope::kinetic_energy_j() const {
  double e = 0;
  for (int i = 0; i < n_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Eigen::Matrix3d r = q_[k].toRotationMatrix();
    const Vec3 wb = r.transpose() * w_[k];
    e += 0.5 * p_.mass_kg * v_[k].squaredNorm() + 0.5 * wb.dot(inertia_body_.cwiseProduct(wb));
  }
  return e;
}

Vec3 ArticulatedRope::point(int segment, double fraction) const {
  segment = std::clamp(segment, 0, n_ - 1);
  return x_[static_cast<std::size_t>(segment)] + (2.0 * fraction - 1.0) * half_m_ * axis(segment);
}

Vec3 ArticulatedRope::point_velocity(int segment, double fraction) const {
  segment = std::clamp(segment, 0, n_ - 1);
  const std::size_t k = static_cast<std::size_t>(segment);
  return v_[k] + w_[k].cross(point(segment, fraction) - x_[k]);
}

void ArticulatedRope::set_point_force(int segment, double fraction, const Vec3& force_n) {
  grasp_active_ = true;
  grasp_segment_ = std::clamp(segment, 0, std::max(n_ - 1, 0));
  grasp_fraction_ = std::clamp(fraction, 0.0, 1.0);
  grasp_force_n_ = force_n;
}

bool ArticulatedRope::pay_out_at_start() {
  if (n_ == 0 || n_ >= p_.max_segments || ends_.end_fixed) return false;
  // The rope slides along its own path out of the spool: each capsule moves
  // into the place of the next, so the path keeps its shape and only the free
  // end moves on, one capsule along its own axis (the new last capsule, a copy
  // of the old one moved on). Shifting the whole rope along its first capsule
  // instead swung a bent rope's free end away from the hand's pull.
  const std::size_t last = static_cast<std::size_t>(n_ - 1), next = static_cast<std::size_t>(n_);
  x_[next] = x_[last] + 2.0 * half_m_ * axis_[last];
  q_[next] = q_[last];
  axis_[next] = axis_[last];
  inv_inertia_[next] = inv_inertia_[last];
  v_[next] = v_[last];
  w_[next] = w_[last];
  ++n_;
  if (grasp_active_) ++grasp_segment_;  // the grasped rope slid on one capsule
  update_vertices();
  return true;
}

double ArticulatedRope::max_joint_gap_m() const {
  double gap = 0;
  for (int i = 0; i + 1 < n_; ++i) gap = std::max(gap, (end_b(i) - end_a(i + 1)).norm());
  if (n_ > 0 && ends_.start_fixed) gap = std::max(gap, (end_a(0) - ends_.start_m).norm());
  if (n_ > 0 && ends_.end_fixed) gap = std::max(gap, (end_b(n_ - 1) - ends_.end_m).norm());
  return gap;
}

}  // namespace visvol::rt
