// The force-directed rope (paper, section 4): a mechanical rope the visibility
// field pushes towards hidden (k1 < 0) or exposed (k1 > 0) ground, refined by
// an operator pulling a grasped point.
//
// Two models share this interface: SpringMassRope (the paper's modified Verlet
// chain of particles, extensible) and ArticulatedRope (rigid capsules joined by
// spherical joints with bending and twisting springs, inextensible).
//
// Units: positions in metres of the pack's CRS (world x east, y north, z up),
// time in seconds, forces in newtons, masses in kilograms.
//
// Real-time contract: everything is sized at construction for max_segments;
// reset(), step(), the accessors and the interaction calls never allocate,
// lock or log. One thread at a time.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>

#include "base/status.hpp"

namespace visvol::rt {

using Vec3 = Eigen::Vector3d;

enum class RopeModel : std::uint8_t { spring = 0, articulated = 1 };
const char* to_string(RopeModel model);
Result<RopeModel> parse_rope_model(const char* text);

// What the world does to the rope: an acceleration (m/s^2) at a point, the sum
// of the weighted field forces (k1 grad F_p, k2 terrain force field,
// constraint forces). Implementations must be real-time safe.
class RopeEnvironment {
 public:
  virtual ~RopeEnvironment() = default;
  virtual Vec3 acceleration(const Vec3& p_m) const = 0;
};

struct RopeParams {
  RopeModel model = RopeModel::articulated;
  int max_segments = 512;             // capacity reserved at construction
  double mass_kg = 1.0;               // per segment (capsule) or per particle
  double linear_damping_per_s = 6.0;  // viscous drag: dv/dt = -c v
  double angular_damping_per_s = 6.0;
  // Articulated: joint springs per radian of relative rotation, and joint damping.
  double bend_stiffness_n_m_per_rad = 400.0;
  double twist_stiffness_n_m_per_rad = 40.0;
  double joint_damping_n_m_s_per_rad = 2.0;  // of the relative bending spin
  double twist_damping_n_m_s_per_rad = 0.2;  // of the relative twisting spin
  double capsule_radius_m = 1.0;             // for the inertia only
  int projection_iterations = 2;             // position projections after each step
  // Articulated, offline minimisation only (the planner; the console's rope
  // stays physical): FIRE, molecular dynamics' minimiser. 0: off. Otherwise,
  // at each step where the applied forces do no positive work every velocity
  // is zeroed; where they do, the capsules' velocities are turned towards
  // their forces by this share (v <- (1 - a) v + a |v| F / |F|, norms over
  // the whole rope), the share shrinking 1% a step after five such steps.
  // Never adds energy. In [0, 1].
  double fire_mixing = 0.0;
  // Spring-mass (paper): stretch springs K_S, K_V, bending springs between i and
  // i + 2, and the Verlet damping factor d in [0, 1].
  double stretch_stiffness_n_per_m = 4000.0;
  double stretch_damping_n_s_per_m = 20.0;
  double bend_spring_n_per_m = 400.0;
  double verlet_damping = 0.004;
  double rest_length_factor = 1.0;  // spring rest length / initial segment length
};

// Checks ranges (finite, positive, capacity) before a rope is made.
Status validate(const RopeParams& params);
// The same checks without a message: real-time safe.
bool params_valid(const RopeParams& params);

// Where the rope is held.
struct RopeEnds {
  bool start_fixed = true;
  bool end_fixed = true;
  Vec3 start_m = Vec3::Zero();  // used when fixed
  Vec3 end_m = Vec3::Zero();
};

class Rope {
 public:
  virtual ~Rope() = default;

  // Lays the rope along a polyline, resampled by arc length into `segments`
  // equal segments (1..max_segments, 2.. for the spring-mass model), at rest.
  // The polyline's ends become the rope's ends. Errors
  // (Errc::invalid_argument) for what check_polyline() refuses; the rope is
  // unchanged. Only a refusal builds a message: real-time callers ask
  // check_polyline() first.
  virtual Status reset(const Vec3* polyline, int points, int segments) = 0;

  virtual void set_ends(const RopeEnds& ends) = 0;
  virtual const RopeEnds& ends() const = 0;

  // One time step of dt_s seconds in the environment.
  virtual void step(double dt_s, const RopeEnvironment& env) = 0;

  // The rope as a polyline of segments + 1 vertices.
  virtual int segments() const = 0;
  virtual const Vec3* vertices() const = 0;
  virtual double kinetic_energy_j() const = 0;
  virtual double length_m() const = 0;

  // A point of the rope, by segment and fraction along it (0..1), its velocity,
  // and an external force on it for the next steps (the grasp coupling).
  virtual Vec3 point(int segment, double fraction) const = 0;
  virtual Vec3 point_velocity(int segment, double fraction) const = 0;
  virtual void set_point_force(int segment, double fraction, const Vec3& force_n) = 0;
  virtual void clear_point_force() = 0;

  // Mode B: pays out one more segment (the current segment length) from the
  // spool at the start. The rope slides along its own path: the path keeps
  // its shape and the free end moves on by one segment along the last one
  // False at capacity, or with the far end held (it must be free).
  virtual bool pay_out_at_start() = 0;

  virtual RopeModel model() const = 0;
  virtual const RopeParams& params() const = 0;
  // New springs, dampers and masses for a rope of the same model and capacity
  // (a console changing stiffness, or resizing segments): springs and dampers
  // act from the next step, mass and capsule radius from the next reset().
  // Errc::invalid_argument (the rope unchanged) for another model or capacity
  // or values validate() refuses. Real-time safe.
  virtual Errc set_params(const RopeParams& params) = 0;
};

// A rope of the given model with capacity params.max_segments (validated).
Result<std::unique_ptr<Rope>> make_rope(const RopeParams& params);

// Shortest segment a rope may have, m: shorter ones are finer than any field
// and unstable at a 1 ms step (ends 1 m apart with 256 segments diverged).
inline constexpr double kMinSegmentM = 0.5;

// Whether a rope of `segments` segments (min_segments..max_segments) can be
// laid along `polyline`: at least 2 points, all finite, and segments of at
// least kMinSegmentM. Errc::invalid_argument when not; real-time safe.
Errc check_polyline(const Vec3* polyline, int points, int segments, int min_segments, int max_segments);
// The same check with a message naming the problem (offline, allocates).
Status describe_polyline(const Vec3* polyline, int points, int segments, int min_segments, int max_segments);

// Lays `segments` + 1 points along `polyline` at equal arc-length spacing into
// `out` (capacity segments + 1). Real-time safe once check_polyline() passed.
Status resample_polyline(const Vec3* polyline, int points, int segments, Vec3* out);

}  // namespace visvol::rt
