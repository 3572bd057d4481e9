#include "rt/rope/planner.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/tolerances.hpp"

namespace visvol::rt {

const char* to_string(Objective objective) { return objective == Objective::hide ? "hide" : "show"; }

Status validate(const PlanRequest& r) {
  std::ostringstream msg;
  if (!r.from.allFinite() || !r.to.allFinite())
    return invalid_argument("plan: --from and --to must be finite X Y Z (m)");
  if ((r.from - r.to).norm() < 1e-6) return invalid_argument("plan: --from and --to are the same point");
  if (r.segments < 2 || r.segments > kMaxPlanSegments) {
    msg << "plan: " << r.segments << " segments is outside 2.." << kMaxPlanSegments;
    return invalid_argument(msg.str());
  }
  const double apart_m = (r.from - r.to).norm();
  if (apart_m / r.segments < kMinSegmentM) {
    const int most = static_cast<int>(std::floor(apart_m / kMinSegmentM));
    msg << "plan: --from and --to are " << apart_m << " m apart: ";
    if (most < 2) {
      msg << "a path needs them at least " << 2 * kMinSegmentM << " m apart";
    } else {
      msg << r.segments << " --segments would be shorter than " << kMinSegmentM << " m; use at most " << most
          << " segments, or ends farther apart";
    }
    return invalid_argument(msg.str());
  }
  const struct {
    double v;
    const char* name;
    double lo, hi;
  } ranges[] = {{r.candidate_interval_s, "candidate interval", 1.0e-3, 1.0e3},
                {r.visibility_gain, "visibility gain (--k1)", 0.0, 1.0e3},
                {r.terrain_gain, "terrain gain (--k2)", 0.0, 1.0e3},
                {r.stiffness, "stiffness (--stiffness)", 1.0e-3, 1.0e3},
                {r.slack < 0 ? 0.0 : r.slack, "slack (--slack)", 0.0, 10.0},
                {r.length_weight, "length weight (--length-weight)", 0.0, 1.0e3},
                {r.dt_s, "time step", 1.0e-5, 0.01},
                {r.max_seconds_per_level, "seconds per level (--max-seconds)", 1.0e-3, 1.0e5}};
  for (const auto& c : ranges) {
    if (!(std::isfinite(c.v) && c.v >= c.lo && c.v <= c.hi)) {
      msg << "plan: " << c.name << " " << c.v << " is outside " << c.lo << ".." << c.hi;
      return invalid_argument(msg.str());
    }
  }
  // The rope's steps cannot be interrupted within a level: bound their work.
  // at the smallest step the planner may take (kMinPlanStep_s, or a smaller request)
  const double vertex_steps = (r.segments + 1.0) * (r.max_seconds_per_level / std::min(r.dt_s, kMinPlanStep_s));
  if (vertex_steps > kMaxVertexStepsPerLevel) {
    msg.precision(3);
    msg << "plan: " << r.segments << " segments for " << r.max_seconds_per_level << " simulated s a level is "
        << vertex_steps << " vertex steps a level, over the " << kMaxVertexStepsPerLevel
        << " allowed (about half a minute of wall time a level): use fewer "
        << "--segments or a smaller --max-seconds";
    return invalid_argument(msg.str());
  }
  if (r.fc_samples < 2 || r.fc_samples > 1000000) return invalid_argument("plan: F_c samples must be 2..1000000");
  if (r.init == InitialPath::polyline) {
    if (r.polyline.size() < 2) return invalid_argument("plan: an initial path needs at least 2 points");
    for (std::size_t i = 0; i < r.polyline.size(); ++i) {
      if (!r.polyline[i].allFinite()) {
        msg << "plan: initial path point " << i << " is not finite";
        return invalid_argument(msg.str());
      }
      if (r.planning_bounds && !r.planning_bounds->contains(r.polyline[i].x(), r.polyline[i].y())) {
        msg.precision(1);
        msg << std::fixed << "plan: initial path point " << i << " (" << r.polyline[i].x() << ", " << r.polyline[i].y()
            << ") is outside the pack's planning bounds";
        return invalid_argument(msg.str());
      }
    }
  }
  VISVOL_RETURN_IF_ERROR(validate(r.envelope));
  if (r.thinning) {
    for (double tol : {r.thinning->horizontal_m, r.thinning->vertical_m}) {
      if (!(std::isfinite(tol) && tol > 0 && tol <= 100.0)) {
        msg << "plan: a waypoint thinning tolerance of " << tol << " m is outside (0, 100] m";
        return invalid_argument(msg.str());
      }
    }
  }
  int per_kind[2] = {0, 0};
  for (const ConstraintPoint& c : r.constraints) {
    if (!c.point_m.allFinite() || !std::isfinite(c.eye_height_m)) {
      return invalid_argument(std::string("plan: --") + to_string(c.kind) + " must be finite");
    }
    if (++per_kind[static_cast<int>(c.kind)] > kMaxPlanObservers) {
      msg << "plan: more than " << kMaxPlanObservers << " --" << to_string(c.kind) << " points";
      return invalid_argument(msg.str());
    }
  }
  if (!(std::isfinite(r.curvature_coeff) && r.curvature_coeff >= 0 && r.curvature_coeff <= 1)) {
    return invalid_argument("plan: the curvature coefficient must be in 0..1");
  }
  if (r.planning_bounds) {
    for (const Vec3* p : {&r.from, &r.to}) {
      if (!r.planning_bounds->contains(p->x(), p->y())) {
        msg.precision(2);
        msg << std::fixed << "plan: " << (p == &r.from ? "--from" : "--to") << " (" << p->x() << ", " << p->y()
            << ") is outside the pack's planning bounds (" << fields::describe_inward(*r.planning_bounds)
            << "), where F_p undercounts observers beyond the DEM";
        return invalid_argument(msg.str());
      }
    }
  }
  return Status::ok_status();
}

namespace detail {

Status check_ends(const PlanRequest& r, const PathChecker& checker, double top_m) {
  const fields::Heightfield& t = checker.terrain();
  const VehicleEnvelope& e = r.envelope;
  for (const Vec3* p : {&r.from, &r.to}) {
    const char* name = p == &r.from ? "--from" : "--to";
    std::ostringstream msg;
    msg.precision(1);
    msg << std::fixed << name << ": ";
    const double i = t.i_of(p->x()), j = t.j_of(p->y());
    if (!(i >= 0 && j >= 0 && i <= t.nx - 1 && j <= t.ny - 1)) {
      msg << "(" << p->x() << ", " << p->y() << ") is outside the pack (x " << t.x_of(0) << ".." << t.x_of(t.nx - 1)
          << ", y " << t.y_of(t.ny - 1) << ".." << t.y_of(0) << ")";
      return invalid_argument(msg.str());
    }
    const double h = p->z() - checker.ground_m(p->x(), p->y());
    if (h < 0) {
      msg << -h << " m below the terrain";
      return invalid_argument(msg.str());
    }
    if (h < e.clearance_m - kHeightTolM) {
      msg << h << " m above the terrain, under the clearance " << e.clearance_m << " m";
      return invalid_argument(msg.str());
    }
    if (h > e.max_agl_m + kHeightTolM) {
      msg << h << " m above the terrain, over --max-agl " << e.max_agl_m << " m";
      return invalid_argument(msg.str());
    }
    if (p->z() > e.max_altitude_m + kHeightTolM) {
      msg << p->z() << " m high, over --max-altitude " << e.max_altitude_m << " m";
      return invalid_argument(msg.str());
    }
    if (p->z() > top_m + kHeightTolM) {
      msg << p->z() << " m high, over the field's top " << top_m << " m";
      return invalid_argument(msg.str());
    }
  }
  return Status::ok_status();
}

bool better(const PathCheck& a, const PathCheck& b, Objective objective) {
  if (a.all_met != b.all_met) return a.all_met;
  if (!a.all_met) {
    // Safety first: of paths that meet not everything, the one the vehicle
    // flies (clearance, ceilings, slopes, turns, bounds), then the one the
    // observers see least against their requirements. A sum alone traded a
    // 30 m clearance down to 26 m on a seventh of a Taunus path for 15
    // observers' fractions.
    if (std::abs(a.flight_violation - b.flight_violation) > PathCheck::kViolationTie) {
      return a.flight_violation < b.flight_violation;
    }
    if (std::abs(a.violation - b.violation) > PathCheck::kViolationTie) return a.violation < b.violation;
  }
  return objective == Objective::hide ? a.fc < b.fc : a.fc > b.fc;
}

std::vector<const PointHull*> ObserverHulls::of(ConstraintKind kind) const {
  const std::optional<PointHull>& h = kind == ConstraintKind::hidden_from ? hidden_from : visible_to;
  return h ? std::vector<const PointHull*>{&*h} : std::vector<const PointHull*>{};
}

}  // namespace detail

RopeParams scaled_rope_params(RopeModel model, int segments, double segment_m, double stiffness, double accel_ref) {
  RopeParams p;
  p.model = model;
  p.max_segments = std::max(segments, 2);
  p.mass_kg = 1.0;
  p.linear_damping_per_s = 6.0;
  p.angular_damping_per_s = 6.0;
  const double l = std::max(segment_m, 1e-3);
  // Springs sized against the field: at stiffness 1, a full-strength force bends
  // a joint by about a radian, or stretches a spring of an 8-segment rope by
  // half its length.
  // A fat capsule keeps the axial (twist) inertia within a factor of a few of
  // the bending one, so one time step suits both.
  p.capsule_radius_m = 0.25 * l;
  const double r = p.capsule_radius_m;
  const double i_perp = p.mass_kg * (3 * r * r + l * l) / 12.0;
  const double i_axial = p.mass_kg * r * r / 2.0;
  p.bend_stiffness_n_m_per_rad = stiffness * 0.3 * p.mass_kg * accel_ref * l;
  p.twist_stiffness_n_m_per_rad = 0.1 * p.bend_stiffness_n_m_per_rad;
  p.joint_damping_n_m_s_per_rad = 0.6 * std::sqrt(p.bend_stiffness_n_m_per_rad * i_perp);
  p.twist_damping_n_m_s_per_rad = 0.6 * std::sqrt(p.twist_stiffness_n_m_per_rad * i_axial);
  // Tension accumulates along the chain: a pull on the whole rope loads the
  // end springs about segments / 2 times more than one segment's force.
  p.stretch_stiffness_n_per_m = stiffness * 2.0 * p.mass_kg * accel_ref / l * std::max(1.0, segments / 8.0);
  p.stretch_damping_n_s_per_m = 0.6 * std::sqrt(p.stretch_stiffness_n_per_m * p.mass_kg);
  p.bend_spring_n_per_m = 0.2 * p.stretch_stiffness_n_per_m;
  p.verlet_damping = 0.0;
  return p;
}

double stable_step_s(const RopeParams& p, double accel_ref, double clearance_margin_m) {
  double omega2 = 0;  // 1/s^2
  if (p.model == RopeModel::spring) {
    // a chain's highest mode: twice one spring's frequency (the stiffer of the
    // stretch springs and the i..i+2 bending springs)
    omega2 = 4.0 * std::max(p.stretch_stiffness_n_per_m, p.bend_spring_n_per_m) / p.mass_kg;
  } else {
    const double r = p.capsule_radius_m, l = 4.0 * r;  // scaled_rope_params: r = l / 4
    const double i_perp = p.mass_kg * (3 * r * r + l * l) / 12.0;
    omega2 = 4.0 * p.bend_stiffness_n_m_per_rad / i_perp;
  }
  // the clearance push: kSaturation reference accelerations per half margin
  omega2 = std::max(omega2, 2.0 * 3.0 * accel_ref / std::max(clearance_margin_m, 1e-3));
  return omega2 > 0 ? 0.4 / std::sqrt(omega2) : 1.0;
}

std::vector<Vec3> with_slack(const std::vector<Vec3>& polyline, double length_m) {
  constexpr int kSegments = 64;
  std::vector<Vec3> base(kSegments + 1);
  if (!resample_polyline(polyline.data(), static_cast<int>(polyline.size()), kSegments, base.data()).ok()) {
    return polyline;
  }
  auto lifted = [&](double amplitude) {
    std::vector<Vec3> out = base;
    for (int i = 0; i <= kSegments; ++i)
      out[static_cast<std::size_t>(i)].z() += amplitude * std::sin(M_PI * i / kSegments);
    return out;
  };
  auto length = [](const std::vector<Vec3>& p) {
    double l = 0;
    for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
    return l;
  };
  if (length(base) >= length_m) return base;
  double lo = 0, hi = length_m;  // a bulge as high as the rope is long is always enough
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (length(lifted(mid)) < length_m ? lo : hi) = mid;
  }
  return lifted(hi);
}

}  // namespace visvol::rt
