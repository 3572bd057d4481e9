#include "rt/rope/vehicle.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace visvol::rt {

const char* to_string(VehicleType type) { return type == VehicleType::multirotor ? "multirotor" : "fixed-wing"; }

const char* to_string(Autopilot autopilot) { return autopilot == Autopilot::ardupilot ? "ardupilot" : "px4"; }

bool parse_autopilot(const std::string& text, Autopilot& out) {
  for (Autopilot a : {Autopilot::px4, Autopilot::ardupilot}) {
    if (text == to_string(a)) {
      out = a;
      return true;
    }
  }
  return false;
}

Result<VehicleEnvelope> vehicle_preset(const std::string& name) {
  VehicleEnvelope v;
  if (name == "fixed-wing") return v;
  if (name == "multirotor") {
    v.name = name;
    v.type = VehicleType::multirotor;
    v.speed_m_per_s = 8.0;
    v.max_climb_deg = 60.0;
    v.max_descent_deg = 45.0;
    v.min_turn_radius_m = 0.0;
    v.acceptance_radius_m = 0.0;
    v.max_wind_m_per_s = 0.0;  // it reaches each waypoint
    return v;
  }
  return invalid_argument("vehicle: '" + name + "' is neither fixed-wing, multirotor nor a file");
}

Status validate(const VehicleEnvelope& v) {
  std::ostringstream msg;
  auto bad = [&](const char* key, double value, const char* what) {
    msg << "vehicle " << v.name << ": " << key << " " << value << " " << what;
    return invalid_argument(msg.str());
  };
  // at least 0.1 m/s: a speed of 5e-324 m/s gave an exposure time of inf s
  if (!(std::isfinite(v.speed_m_per_s) && v.speed_m_per_s >= 0.1 && v.speed_m_per_s <= 1000)) {
    return bad("speed", v.speed_m_per_s, "is outside [0.1, 1000] m/s");
  }
  if (!(v.max_climb_deg > 0 && v.max_climb_deg <= 90))
    return bad("max-climb", v.max_climb_deg, "is outside (0, 90] deg");
  if (!(v.max_descent_deg > 0 && v.max_descent_deg <= 90)) {
    return bad("max-descent", v.max_descent_deg, "is outside (0, 90] deg");
  }
  if (!(std::isfinite(v.min_turn_radius_m) && v.min_turn_radius_m >= 0 && v.min_turn_radius_m <= 1e5)) {
    return bad("min-turn-radius", v.min_turn_radius_m, "is outside [0, 100000] m");
  }
  if (!(std::isfinite(v.acceptance_radius_m) && v.acceptance_radius_m >= 0 && v.acceptance_radius_m <= 1e4)) {
    return bad("acceptance-radius", v.acceptance_radius_m, "is outside [0, 10000] m");
  }
  if (!(std::isfinite(v.max_wind_m_per_s) && v.max_wind_m_per_s >= 0 && v.max_wind_m_per_s <= 100)) {
    return bad("max-wind", v.max_wind_m_per_s, "is outside [0, 100] m/s");
  }
  if (!(std::isfinite(v.clearance_m) && v.clearance_m >= 0 && v.clearance_m <= 1e4)) {
    return bad("clearance", v.clearance_m, "is outside [0, 10000] m");
  }
  if (!(v.max_agl_m > 0 && v.max_agl_m <= VehicleEnvelope::kNone))
    return bad("max-agl", v.max_agl_m, "is not above 0 m");
  if (!(v.max_agl_m > v.clearance_m)) {
    msg << "vehicle " << v.name << ": max-agl " << v.max_agl_m << " m is not above the clearance " << v.clearance_m
        << " m: no height is allowed";
    return invalid_argument(msg.str());
  }
  // none (infinite), or a height as the console's option takes it: -1e300 m
  // was accepted, a ceiling no path can be under
  if (v.max_altitude_m != VehicleEnvelope::kNone &&
      !(std::isfinite(v.max_altitude_m) && std::fabs(v.max_altitude_m) <= VehicleEnvelope::kMaxAltitudeRangeM)) {
    return bad("max-altitude", v.max_altitude_m, "is not a height in -100000..100000 m");
  }
  return Status::ok_status();
}

double switch_distance_m(const VehicleEnvelope& e) {
  if (!(e.acceptance_radius_m > 0)) return 0.0;
  if (!is_px4_fixed_wing(e)) return e.acceptance_radius_m;
  return e.acceptance_radius_m * (e.speed_m_per_s + e.max_wind_m_per_s) / e.speed_m_per_s;
}

double altitude_hold_m(const VehicleEnvelope& e) {
  const double switch_m = switch_distance_m(e);
  if (!(switch_m > 0)) return 0.0;
  return is_px4_fixed_wing(e) ? std::max(switch_m, kPx4LoiterRadiusM) : switch_m;
}

}  // namespace visvol::rt
