#include "app/mission_options.hpp"

#include <toml++/toml.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <tuple>

#include "io/input_file.hpp"

namespace visvol::cli {

namespace {

constexpr std::size_t kMaxVehicleFileBytes = 64 * 1024;

// A number under `key` (an integer is taken as one too), or an error.
Status read_number(const toml::node& node, const std::string& file, const std::string& key, double& out) {
  if (const auto* f = node.as_floating_point()) {
    out = f->get();
  } else if (const auto* i = node.as_integer()) {
    out = static_cast<double>(i->get());
  } else {
    return invalid_argument(file + ": " + key + " must be a number");
  }
  return Status::ok_status();
}

}  // namespace

Result<rt::VehicleEnvelope> read_vehicle_file(const std::string& path) {
  Result<std::string> text = read_input_file(path, kMaxVehicleFileBytes);
  if (!text.ok()) return text.status();
  toml::table table;
  try {
    table = toml::parse(*text, path);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    return invalid_argument(path + ":" + std::to_string(where.line) + ":" + std::to_string(where.column) + ": " +
                            std::string(e.description()));
  }
  // the type first: it picks the preset the other keys change
  std::string type = "fixed-wing";
  if (const toml::node* t = table.get("type")) {
    const auto* s = t->as_string();
    if (!s) return invalid_argument(path + ": type must be \"fixed-wing\" or \"multirotor\"");
    type = s->get();
  }
  Result<rt::VehicleEnvelope> v = rt::vehicle_preset(type);
  if (!v.ok()) return invalid_argument(path + ": type \"" + type + "\" is neither fixed-wing nor multirotor");
  v->name = path;
  const struct {
    const char* key;
    double rt::VehicleEnvelope::*field;
  } numbers[] = {{"speed", &rt::VehicleEnvelope::speed_m_per_s},
                 {"max-climb", &rt::VehicleEnvelope::max_climb_deg},
                 {"max-descent", &rt::VehicleEnvelope::max_descent_deg},
                 {"min-turn-radius", &rt::VehicleEnvelope::min_turn_radius_m},
                 {"clearance", &rt::VehicleEnvelope::clearance_m},
                 {"max-agl", &rt::VehicleEnvelope::max_agl_m},
                 {"max-altitude", &rt::VehicleEnvelope::max_altitude_m},
                 {"acceptance-radius", &rt::VehicleEnvelope::acceptance_radius_m},
                 {"max-wind", &rt::VehicleEnvelope::max_wind_m_per_s}};
  for (const auto& [key, node] : table) {
    const std::string k(key.str());
    if (k == "type") continue;
    if (k == "name") {
      const auto* s = node.as_string();
      if (!s) return invalid_argument(path + ": name must be a string");
      // printed in reports and on terminals: no control characters (an escape
      // sequence in a vehicle file would drive the operator's terminal), C1's
      // in UTF-8 (0xC2 0x80..0x9F) included
      const std::string& name = s->get();
      bool control = false;
      for (std::size_t i = 0; i < name.size(); ++i) {
        const auto c = static_cast<unsigned char>(name[i]);
        const bool c1 = c == 0xC2 && i + 1 < name.size() && static_cast<unsigned char>(name[i + 1]) >= 0x80 &&
                        static_cast<unsigned char>(name[i + 1]) <= 0x9F;
        control = control || c < 0x20 || c == 0x7F || c1;
      }
      if (name.size() > 128 || control) {
        return invalid_argument(path + ": name must be at most 128 bytes, none of them a control character");
      }
      v->name = name;
      continue;
    }
    if (k == "autopilot") {
      const auto* s = node.as_string();
      if (!s || !rt::parse_autopilot(s->get(), v->autopilot)) {
        return invalid_argument(path + ": autopilot must be \"px4\" or \"ardupilot\"");
      }
      continue;
    }
    bool known = false;
    for (const auto& n : numbers) {
      if (k != n.key) continue;
      VISVOL_RETURN_IF_ERROR(read_number(node, path, k, (*v).*(n.field)));
      known = true;
    }
    if (!known) {
      return invalid_argument(path + ": unknown key '" + k +
                              "' (known: name, type, autopilot, speed, max-climb, max-descent, min-turn-radius, "
                              "clearance, max-agl, max-altitude, acceptance-radius, max-wind)");
    }
  }
  const Status valid = rt::validate(*v);
  if (!valid.ok()) return invalid_argument(path + ": " + valid.message());
  return v;
}

void add_envelope_options(CLI::App& c, EnvelopeOptions& o) {
  c.add_option("--vehicle", o.vehicle,
               "fixed-wing (20 m/s, climb and descent 15 deg, turns 80 m, waypoints taken 100 m early, planned "
               "for up to 5 m/s of wind: 125 m), multirotor (8 "
               "m/s, climb 60 deg, "
               "descent 45 deg) or a TOML file of the keys below")
      ->capture_default_str();
  c.add_option("--speed", o.speed_m_per_s, "Cruise speed, m/s (exposure time, mission speeds)");
  c.add_option("--max-climb", o.max_climb_deg, "Steepest climb of a segment, deg");
  c.add_option("--max-descent", o.max_descent_deg, "Steepest descent of a segment, deg");
  c.add_option("--min-turn-radius", o.min_turn_radius_m, "Tightest turn at a waypoint, m (0: none)");
  c.add_option("--clearance", o.clearance_m, "Least height above the terrain, m (default 30)");
  c.add_option("--max-agl", o.max_agl_m,
               "Highest height above the terrain, m (default none; a planned path stays under the field's top)");
  c.add_option("--max-altitude", o.max_altitude_m, "Highest height above the DEM's datum, m");
  c.add_option("--acceptance-radius", o.acceptance_radius_m,
               "How far before a waypoint the autopilot takes the next one and its altitude at cruise speed, m: "
               "the path clears the ground this far behind each point (a PX4 fixed-wing: grown by --max-wind, "
               "and at least 80 m), and a leg no longer than that at its lower end from this far before its start "
               "(fixed-wing 100, multirotor 0)");
  c.add_option("--max-wind", o.max_wind_m_per_s,
               "The strongest wind the mission is flown in, m/s (0..100): a PX4 fixed-wing takes each waypoint "
               "(speed + wind) / speed times the acceptance radius early, as its switch distance grows with its "
               "ground speed; ArduPlane switches at the mission's radius (fixed-wing 5, multirotor 0)");
  c.add_option("--autopilot", o.autopilot,
               "The vehicle's flight stack, px4 or ardupilot: a .plan mission's firmware (default: the vehicle's)");
}

void add_constraint_options(CLI::App& c, ConstraintOptions& o) {
  c.add_option("--hidden-from", o.hidden_from,
               "Stay hidden from an observer standing at X Y Z (pack CRS, m; at or above the terrain); repeatable")
      ->expected(3)
      ->allow_extra_args(false);
  c.add_option("--visible-to", o.visible_to, "Stay visible to an observer at X Y Z; repeatable")
      ->expected(3)
      ->allow_extra_args(false);
  c.add_option("--eye-height", o.eye_height_m, "Observers' eyes above the points named, m")->capture_default_str();
}

Result<rt::VehicleEnvelope> resolve_envelope(const EnvelopeOptions& o) {
  Result<rt::VehicleEnvelope> v = o.vehicle == "fixed-wing" || o.vehicle == "multirotor" ? rt::vehicle_preset(o.vehicle)
                                                                                         : read_vehicle_file(o.vehicle);
  if (!v.ok()) return invalid_argument("--vehicle " + v.status().message());
  const struct {
    const std::optional<double>& value;
    double rt::VehicleEnvelope::*field;
  } overrides[] = {{o.speed_m_per_s, &rt::VehicleEnvelope::speed_m_per_s},
                   {o.max_climb_deg, &rt::VehicleEnvelope::max_climb_deg},
                   {o.max_descent_deg, &rt::VehicleEnvelope::max_descent_deg},
                   {o.min_turn_radius_m, &rt::VehicleEnvelope::min_turn_radius_m},
                   {o.clearance_m, &rt::VehicleEnvelope::clearance_m},
                   {o.max_agl_m, &rt::VehicleEnvelope::max_agl_m},
                   {o.max_altitude_m, &rt::VehicleEnvelope::max_altitude_m},
                   {o.acceptance_radius_m, &rt::VehicleEnvelope::acceptance_radius_m},
                   {o.max_wind_m_per_s, &rt::VehicleEnvelope::max_wind_m_per_s}};
  for (const auto& x : overrides) {
    if (x.value) (*v).*(x.field) = *x.value;
  }
  if (o.autopilot && !rt::parse_autopilot(*o.autopilot, v->autopilot)) {
    return invalid_argument("--autopilot: '" + *o.autopilot + "' is neither px4 nor ardupilot");
  }
  const Status valid = rt::validate(*v);
  if (!valid.ok()) return invalid_argument(valid.message());
  return v;
}

Result<std::vector<rt::ConstraintPoint>> constraint_points(const ConstraintOptions& o) {
  // checked with or without observers: a bad value is a mistake either way
  if (!(std::isfinite(o.eye_height_m) && o.eye_height_m >= 0 && o.eye_height_m <= 10000)) {
    return invalid_argument("--eye-height " + std::to_string(o.eye_height_m) + " is outside 0..10000 m");
  }
  std::vector<rt::ConstraintPoint> out;
  for (const auto& [points, kind, option] :
       {std::tuple{&o.hidden_from, rt::ConstraintKind::hidden_from, "--hidden-from"},
        std::tuple{&o.visible_to, rt::ConstraintKind::visible_to, "--visible-to"}}) {
    for (const std::vector<double>& p : *points) {
      if (p.size() != 3 || !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        return invalid_argument(std::string(option) + ": a point is three finite numbers X Y Z (m)");
      }
      VISVOL_RETURN_IF_ERROR(rt::check_observer_altitude(option, p[2]));
      out.push_back({kind, rt::Vec3(p[0], p[1], p[2]), o.eye_height_m});
    }
  }
  return out;
}

}  // namespace visvol::cli
