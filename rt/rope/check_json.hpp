// The exact path check (rt/rope/path_check.hpp) as JSON: one constraint or
// envelope limit per object, the same keys for `visvol check --json`,
// `visvol plan --json` and the console's summary.json. Offline: allocates.
#pragma once

#include <nlohmann/json.hpp>

#include "rt/rope/path_check.hpp"
#include "rt/rope/vehicle.hpp"

namespace visvol::rt {

// A number, or null where it is not finite (no limit, no turn).
nlohmann::json finite_or_null(double v);
// [x, y, z] in metres.
nlohmann::json point_json(const Vec3& p_m);

// kind, point, eye_m, satisfied_fraction, seen_m (metres of the path seen), met.
nlohmann::json constraint_json(const ConstraintResult& r);
// name, unit, limit, worst (null where not finite), satisfied_fraction, met.
nlohmann::json limit_json(const LimitResult& l);
// The vehicle's envelope: name, type, speed_m_per_s, max_climb_deg,
// max_descent_deg, min_turn_radius_m, clearance_m, max_agl_m, max_altitude_m
// (null: none).
nlohmann::json vehicle_json(const VehicleEnvelope& v);

}  // namespace visvol::rt
