// The spring-mass rope (paper, Fig. 4 A): segments + 1 particles joined by
// stretch springs (K_S, damping K_V) and bending springs between every other
// particle, advanced by the paper's modified Verlet integration
//   X(n+1) = (2 - d) X(n) - (1 - d) X(n-1) + F(n) dt^2 / m.
// The field is sampled at the particles only, so more particles are needed
// than capsules for the same fidelity (the paper's aliasing remark). The rope
// stretches: its length is not fixed.
#pragma once

#include <vector>

#include "rt/rope/rope.hpp"

namespace visvol::rt {

class SpringMassRope final : public Rope {
 public:
  explicit SpringMassRope(const RopeParams& params);

  Status reset(const Vec3* polyline, int points, int segments) override;
  void set_ends(const RopeEnds& ends) override;
  const RopeEnds& ends() const override { return ends_; }
  void step(double dt_s, const RopeEnvironment& env) override;

  int segments() const override { return n_; }
  const Vec3* vertices() const override { return x_.data(); }
  double kinetic_energy_j() const override;
  double length_m() const override;

  Vec3 point(int segment, double fraction) const override;
  Vec3 point_velocity(int segment, double fraction) const override;
  void set_point_force(int segment, double fraction, const Vec3& force_n) override;
  void clear_point_force() override { grasp_active_ = false; }
  bool pay_out_at_start() override;

  RopeModel model() const override { return RopeModel::spring; }
  const RopeParams& params() const override { return p_; }
  Errc set_params(const RopeParams& params) override {
    if (params.model != p_.model || params.max_segments != p_.max_segments || !params_valid(params)) {
      return Errc::invalid_argument;
    }
    p_ = params;
    return Errc::ok;
  }

 private:
  void pin_ends();

  RopeParams p_;
  RopeEnds ends_;
  int n_ = 0;                 // segments; particles are n_ + 1
  double rest_m_ = 1.0;       // stretch spring rest length
  double bend_rest_m_ = 2.0;  // bending spring rest length
  double dt_prev_s_ = 0;      // the last step, for velocities
  std::vector<Vec3> x_, x_prev_, v_, force_;
  bool grasp_active_ = false;
  int grasp_segment_ = 0;
  double grasp_fraction_ = 0;
  Vec3 grasp_force_n_ = Vec3::Zero();
};

}  // namespace visvol::rt
