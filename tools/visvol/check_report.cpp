#include "check_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "rt/rope/check_json.hpp"

namespace visvol::cli {

namespace {

double held_in_sight_s(const Holds& holds, std::size_t k) {
  return k < holds.in_sight_s.size() ? holds.in_sight_s[k] : 0.0;
}

}  // namespace

nlohmann::json check_json(const rt::PathCheck& c, const rt::VehicleEnvelope& e, const Holds& holds,
                          const std::vector<std::string>& more_unmet) {
  nlohmann::json j;
  j["constraints"] = nlohmann::json::array();
  for (std::size_t k = 0; k < c.constraints.size(); ++k) {
    const rt::ConstraintResult& r = c.constraints[k];
    nlohmann::json o = rt::constraint_json(r);
    o["exposure_s"] = r.seen_m / e.speed_m_per_s + held_in_sight_s(holds, k);
    j["constraints"].push_back(std::move(o));
  }
  j["envelope"] = nlohmann::json::array();
  for (const rt::LimitResult& l : c.envelope) j["envelope"].push_back(rt::limit_json(l));
  j["vehicle"] = rt::vehicle_json(e);
  j["inside_planning_bounds"] = c.inside_planning_bounds;
  j["inside_bounds_fraction"] = c.inside_bounds_fraction;
  j["all_met"] = c.all_met && more_unmet.empty();
  std::vector<std::string> unmet = c.unmet();
  unmet.insert(unmet.end(), more_unmet.begin(), more_unmet.end());
  j["unmet"] = unmet;
  j["length_m"] = c.length_m;
  j["duration_s"] = c.duration_s + holds.total_s;
  j["held_s"] = holds.total_s;
  j["fc"] = c.fc;
  return j;
}

nlohmann::json vertices_json(const rt::PathCheck& c, const std::vector<rt::Vec3>& path) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < path.size() && i < c.per_vertex.size(); ++i) {
    const rt::VertexCheck& v = c.per_vertex[i];
    nlohmann::json seen = nlohmann::json::array();
    for (bool s : v.seen_by) seen.push_back(s);
    out.push_back({{"x_m", path[i].x()},
                   {"y_m", path[i].y()},
                   {"z_m", path[i].z()},
                   {"fp", v.fp},
                   {"ground_m", v.ground_m},
                   {"clearance_m", v.clearance_m},
                   {"early_m", rt::finite_or_null(v.early_m)},
                   {"climb_deg", v.climb_deg},
                   {"turn_radius_m", rt::finite_or_null(v.turn_radius_m)},
                   {"seen_by", seen}});
  }
  return out;
}

void print_check(const rt::PathCheck& c, const rt::VehicleEnvelope& e, const Holds& holds,
                 const std::vector<std::string>& more_unmet) {
  if (c.constraints.empty()) {
    // "all met" below would otherwise read as hidden from everyone that matters
    std::printf("constraint none given (--hidden-from, --visible-to): no observer's sight lines checked\n");
  }
  for (std::size_t k = 0; k < c.constraints.size(); ++k) {
    const rt::ConstraintResult& r = c.constraints[k];
    const rt::Vec3& p = r.constraint.point_m;
    const double held_s = held_in_sight_s(holds, k);
    char held[64] = "";
    if (held_s > 0) std::snprintf(held, sizeof held, ", %.0f s of them held", held_s);
    std::printf("constraint %s (%.1f, %.1f, %.1f): holds on %.3f of the length, in sight %.0f m (%.0f s%s) %s\n",
                rt::to_string(r.constraint.kind), p.x(), p.y(), p.z(), rt::fraction_shown(r.satisfied_fraction),
                r.seen_m, r.seen_m / e.speed_m_per_s + held_s, held, r.met ? "met" : "NOT MET");
  }
  for (const rt::LimitResult& l : c.envelope) {
    if (!std::isfinite(l.limit)) {
      std::printf("envelope   %s none: worst %.1f %s\n", l.name.c_str(), l.worst, l.unit.c_str());
      continue;
    }
    const int decimals = rt::worst_decimals(l);  // the limit's too: the worst reads past it
    std::printf("envelope   %s %.*f %s: worst %.*f %s, holds on %.3f of the %slength %s\n", l.name.c_str(), decimals,
                l.limit, l.unit.c_str(), decimals, l.worst, l.unit.c_str(), rt::fraction_shown(l.satisfied_fraction),
                l.name == rt::kFlownClearance ? "flown " : "", l.met ? "met" : "NOT MET");
    if (l.name == "early-descent") {  // what it was judged for: the wind moves it
      std::printf(
          "           judged for waypoints taken %.0f m out (acceptance radius %.0f m at %.1f m/s, %.1f m/s of "
          "wind), heights up to %.0f m early\n",
          rt::switch_distance_m(e), e.acceptance_radius_m, e.speed_m_per_s, e.max_wind_m_per_s, rt::altitude_hold_m(e));
    }
  }
  std::printf("bounds     %.3f of the length inside the planning bounds %s\n",
              rt::fraction_shown(c.inside_bounds_fraction), c.inside_planning_bounds ? "met" : "NOT MET");
  if (c.all_met && more_unmet.empty()) {
    std::printf("requirements all met (%s checked on the finest terrain)\n",
                c.constraints.empty() ? "limits" : "sight lines and limits");
    return;
  }
  std::printf("requirements NOT MET:\n");
  for (const std::string& u : c.unmet()) std::printf("  %s\n", u.c_str());
  for (const std::string& u : more_unmet) std::printf("  %s\n", u.c_str());
}

nlohmann::json flown_json(const std::vector<rt::FlownCheck>& flights) {
  nlohmann::json out = nlohmann::json::array();
  for (const rt::FlownCheck& f : flights) {
    out.push_back({{"ground_speed_m_per_s", f.ground_speed_m_per_s},
                   {"switch_distance_m", f.switch_distance_m},
                   {"altitude_hold_m", f.altitude_hold_m},
                   {"length_m", f.length_m},
                   {"least_clearance_m", rt::finite_or_null(f.least_clearance_m)},
                   {"least_at", rt::point_json(f.least_at_m)},
                   {"clearance_fraction", f.clearance_fraction},
                   {"max_off_path_m", f.max_off_path_m},
                   {"constraint_fractions", f.constraint_fractions},
                   {"reached_end", f.reached_end},
                   {"lowest", f.lowest},
                   {"flights_flown", f.flights_flown}});
  }
  return out;
}

void print_flown(const std::vector<rt::FlownCheck>& flights, const rt::PathCheck& check, const rt::VehicleEnvelope& e) {
  // the flights reported are the ends of those flown (PathChecker::fly)
  const int flown = flights.empty() ? 0 : flights.front().flights_flown;
  if (flown > 2) {
    const double first = flights.front().ground_speed_m_per_s, last = flights.back().ground_speed_m_per_s;
    std::printf(
        "flown      at %d ground speeds, %.1f to %.1f m/s (%.2f m/s apart); shown: still air, the strongest "
        "tailwind and the lowest\n",
        flown, first, last, (last - first) / (flown - 1));
  }
  for (const rt::FlownCheck& f : flights) {
    std::printf(
        "flown      PX4 L1 guidance at %.1f m/s over the ground, waypoints taken %.0f m out, heights held %.0f m "
        "early%s\n",
        f.ground_speed_m_per_s, f.switch_distance_m, f.altitude_hold_m,
        f.reached_end ? "" : ", NOT at the end in time");
    const bool low = f.clearance_fraction < 1;
    std::printf("           least clearance %.1f m at (%.1f, %.1f), %.3f of the flown %.0f m at or above %.0f m%s\n",
                f.least_clearance_m, f.least_at_m.x(), f.least_at_m.y(), rt::fraction_shown(f.clearance_fraction),
                f.length_m, e.clearance_m, low ? ": BELOW it (flown-clearance)" : "");
    std::printf("           %.1f m at most off the planned legs\n", f.max_off_path_m);
    for (std::size_t k = 0; k < f.constraint_fractions.size() && k < check.constraints.size(); ++k) {
      const rt::ConstraintResult& r = check.constraints[k];
      const rt::Vec3& p = r.constraint.point_m;
      std::printf("           constraint %s (%.1f, %.1f, %.1f): holds on %.3f of the flown length (a report)%s\n",
                  rt::to_string(r.constraint.kind), p.x(), p.y(), p.z(), rt::fraction_shown(f.constraint_fractions[k]),
                  f.constraint_fractions[k] < r.satisfied_fraction ? " (less than on the legs)" : "");
    }
  }
}

double circle_clearance_m(const std::function<double(double, double)>& ground_m, const fields::VolumeGeometry& g,
                          double x, double y, double altitude_m, double radius_m) {
  const double x_max = g.origin_x + (g.nx - 1) * g.spacing_m, y_min = g.origin_y - (g.ny - 1) * g.spacing_m;
  const double wanted = std::ceil(2 * M_PI * radius_m / (g.spacing_m / 16));
  const int samples = static_cast<int>(std::clamp(wanted, 72.0, double(1 << 22)));
  double lowest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < samples; ++k) {
    const double a = 2 * M_PI * k / samples;
    const double px = x + radius_m * std::cos(a), py = y + radius_m * std::sin(a);
    if (px < g.origin_x || px > x_max || py < y_min || py > g.origin_y) return -std::numeric_limits<double>::infinity();
    lowest = std::min(lowest, altitude_m - ground_m(px, py));
  }
  return lowest;
}

}  // namespace visvol::cli
