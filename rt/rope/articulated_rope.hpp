// The articulated rope: N rigid capsules joined end to end by spherical joints
// with bending and twisting springs (paper, Fig. 4 B, C).
//
// Each capsule has 6 degrees of freedom (centre, unit quaternion). A step:
//   1. field forces sampled at the capsule ends and middle (Simpson weights):
//      the force is the average over the capsule, the torque about its centre;
//      joint springs and the grasp force are added;
//   2. velocities advance (semi-implicit Euler, implicit viscous damping);
//   3. joint impulses that keep every joint closed are solved exactly: the
//      system J M^-1 J^T is block-tridiagonal along the chain (3 x 3 blocks),
//      solved directly in O(N) (block Thomas algorithm), with a Baumgarte term;
//   4. positions and orientations advance (quaternion exponential map);
//   5. joint gaps left by the linearisation are projected away with the same
//      O(N) solve (params.projection_iterations times).
// Capsules are rigid, so the rope is inextensible: its length is N times the
// capsule length and joint gaps stay below 1e-4 of a capsule.
#pragma once

#include <vector>

#include "rt/rope/rope.hpp"

namespace visvol::rt {

namespace detail {
// [r]x m and m [r]x, with [r]x the cross-product matrix of r, without its
// zero terms: the joint solve forms several per joint and step. Each value is
// the full matrix product's (the same sums with the zero terms left out).
Eigen::Matrix3d cross_times(const Vec3& r, const Eigen::Matrix3d& m);
Eigen::Matrix3d times_cross(const Eigen::Matrix3d& m, const Vec3& r);
// The unit quaternion of rotation vector w (series for small angles).
Eigen::Quaterniond exp_map(const Vec3& w);
// The shortest rotation taking body z onto dir (not zero).
Eigen::Quaterniond from_body_z(const Vec3& dir);
}  // namespace detail

class ArticulatedRope final : public Rope {
 public:
  explicit ArticulatedRope(const RopeParams& params);

  Status reset(const Vec3* polyline, int points, int segments) override;
  void set_ends(const RopeEnds& ends) override { ends_ = ends; }
  const RopeEnds& ends() const override { return ends_; }
  void step(double dt_s, const RopeEnvironment& env) override;

  int segments() const override { return n_; }
  const Vec3* vertices() const override { return vertices_.data(); }
  double kinetic_energy_j() const override;
  double length_m() const override { return n_ * 2.0 * half_m_; }

  Vec3 point(int segment, double fraction) const override;
  Vec3 point_velocity(int segment, double fraction) const override;
  void set_point_force(int segment, double fraction, const Vec3& force_n) override;
  void clear_point_force() override { grasp_active_ = false; }
  bool pay_out_at_start() override;

  RopeModel model() const override { return RopeModel::articulated; }
  const RopeParams& params() const override { return p_; }
  Errc set_params(const RopeParams& params) override {
    if (params.model != p_.model || params.max_segments != p_.max_segments || !params_valid(params)) {
      return Errc::invalid_argument;
    }
    if (params.fire_mixing != p_.fire_mixing) {  // FIRE starts afresh with its new share
      fire_share_ = params.fire_mixing;
      fire_downhill_steps_ = 0;
    }
    p_ = params;
    return Errc::ok;
  }

  // The largest distance between the ends of neighbouring capsules (and
  // between a fixed end and its anchor), metres.
  double max_joint_gap_m() const;

 private:
  struct Attachment {
    int body = -1;  // -1: the world (an anchor)
    Vec3 r;         // attachment point minus the body's centre, world axes
    double sign = 1;
  };
  struct Joint {
    Attachment a, b;  // the constraint keeps point(a) - point(b) at zero
    Vec3 anchor;      // world point when one side is the world
  };

  // The capsule's axis (body z in world axes), cached: read about ten times a
  // step, it changes only where q_ does (refresh_axes()).
  const Vec3& axis(int i) const { return axis_[static_cast<std::size_t>(i)]; }
  Vec3 end_a(int i) const { return x_[static_cast<std::size_t>(i)] - half_m_ * axis(i); }
  Vec3 end_b(int i) const { return x_[static_cast<std::size_t>(i)] + half_m_ * axis(i); }
  void refresh_axes();
  Eigen::Matrix3d inverse_inertia_world(int i) const;

  void build_joints();
  Vec3 attachment_point(const Attachment& at, const Vec3& anchor) const;
  Vec3 joint_error(const Joint& j) const;
  Vec3 joint_velocity(const Joint& j) const;
  // Factors the block-tridiagonal system A = J M^-1 J^T over the joints
  // (block LDU), then solves A lambda = rhs with the factors.
  void factor_chain();
  void solve_chain();
  // Recomputes the joints' attachment vectors after the bodies moved.
  void refresh_attachments();
  void apply_impulses(bool positions);
  void accumulate_forces(const RopeEnvironment& env);
  void add_joint_springs();
  void solve_joint_velocities(double dt_s);
  // FIRE (RopeParams::fire_mixing): after the joint impulses, before the
  // positions; the joints' velocities solved again after.
  void fire_adjust_velocities(double dt_s);
  void update_vertices();

  RopeParams p_;
  RopeEnds ends_;
  int n_ = 0;                     // capsules
  double half_m_ = 0.5;           // half capsule length
  Eigen::Vector3d inertia_body_;  // principal moments, body z along the capsule
  // per capsule
  std::vector<Vec3> x_, v_, w_, force_, torque_;
  std::vector<Eigen::Quaterniond> q_;
  std::vector<Vec3> axis_;  // q_ times body z
  std::vector<Eigen::Matrix3d> inv_inertia_;
  // per sample point: ends and middles, 2 n + 1
  std::vector<Vec3> sample_acc_;
  // per joint (n + 1 at most)
  std::vector<Joint> joints_;
  std::vector<Eigen::Matrix3d> d_inv_, upper_, lower_;
  std::vector<Vec3> rhs_, lambda_;
  int joint_count_ = 0;
  std::vector<Vec3> vertices_;
  // grasp
  bool grasp_active_ = false;
  int grasp_segment_ = 0;
  double grasp_fraction_ = 0;
  Vec3 grasp_force_n_ = Vec3::Zero();
  // FIRE's state: the share mixed in now, steps downhill since the last stop
  double fire_share_ = 0;
  int fire_downhill_steps_ = 0;
};

}  // namespace visvol::rt
