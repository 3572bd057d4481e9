#include "rt/rope/check_json.hpp"

#include <cmath>

namespace visvol::rt {

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json point_json(const Vec3& p_m) { return nlohmann::json::array({p_m.x(), p_m.y(), p_m.z()}); }

nlohmann::json constraint_json(const ConstraintResult& r) {
  return {{"kind", to_string(r.constraint.kind)},
          {"point", point_json(r.constraint.point_m)},
          {"eye_m", point_json(r.constraint.eye_m())},
          {"satisfied_fraction", r.satisfied_fraction},
          {"seen_m", r.seen_m},
          {"met", r.met}};
}

nlohmann::json limit_json(const LimitResult& l) {
  return {{"name", l.name},
          {"unit", l.unit},
          {"limit", finite_or_null(l.limit)},
          {"worst", finite_or_null(l.worst)},
          {"satisfied_fraction", l.satisfied_fraction},
          {"met", l.met}};
}

nlohmann::json vehicle_json(const VehicleEnvelope& v) {
  return {{"name", v.name},
          {"type", to_string(v.type)},
          {"speed_m_per_s", v.speed_m_per_s},
          {"max_climb_deg", v.max_climb_deg},
          {"max_descent_deg", v.max_descent_deg},
          {"min_turn_radius_m", v.min_turn_radius_m},
          {"acceptance_radius_m", v.acceptance_radius_m},
          {"max_wind_m_per_s", v.max_wind_m_per_s},
          {"switch_distance_m", switch_distance_m(v)},
          {"clearance_m", v.clearance_m},
          {"max_agl_m", finite_or_null(v.max_agl_m)},
          {"max_altitude_m", finite_or_null(v.max_altitude_m)},
          {"autopilot", to_string(v.autopilot)}};
}

}  // namespace visvol::rt
