// visvol check PACK PATH: the paper's path assessment for any path (visvol's
// own, a QGroundControl .plan, GeoJSON, CSV, text), checked the independent
// way: exact sight lines and limits on the finest terrain.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/mission_options.hpp"
#include "check_report.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "flown_path.hpp"
#include "io/json_text.hpp"
#include "pack_planner.hpp"  // the planner and sampler for packs: compiled in visvol_pack_planner
#include "path_io.hpp"
#include "planning_pack.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/point_hull_maker.hpp"
#include "storage/planning_bounds.hpp"

namespace visvol::cli {

namespace {

struct CheckOptions {
  std::string pack, path;
  EnvelopeOptions envelope;
  ConstraintOptions constraints;
  bool json = false;
};

// One row per point flown; '#' is the file's vertex, '~' a point of a loiter's circle.
void print_vertices(const rt::PathCheck& c, const std::vector<rt::Vec3>& path, const std::vector<int>& vertex_of) {
  std::printf("%5s %12s %12s %8s %8s %9s %9s %7s %9s  %s\n", "#", "x_m", "y_m", "z_m", "F_p", "clear_m", "early_m",
              "climb", "turn_m", "seen by");
  for (std::size_t i = 0; i < path.size(); ++i) {
    const std::string number = vertex_of[i] >= 0 ? std::to_string(vertex_of[i]) : "~";
    const rt::VertexCheck& v = c.per_vertex[i];
    std::string seen;
    for (std::size_t k = 0; k < v.seen_by.size(); ++k) {
      if (v.seen_by[k]) seen += (seen.empty() ? "" : ",") + std::to_string(k + 1);
    }
    char early[32] = "-";
    if (std::isfinite(v.early_m)) std::snprintf(early, sizeof early, "%.1f", v.early_m);
    std::printf("%5s %12.1f %12.1f %8.1f %8.5f %9.1f %9s %7.1f %9s  %s\n", number.c_str(), path[i].x(), path[i].y(),
                path[i].z(), v.fp, v.clearance_m, early, v.climb_deg,
                std::isfinite(v.turn_radius_m) ? std::to_string(std::lround(v.turn_radius_m)).c_str() : "-",
                seen.empty() ? "-" : seen.c_str());
  }
}

// MAV_TYPEs (a .plan's vehicleType) of multirotors: quadrotor, coaxial,
// helicopter, hexarotor, octorotor, tricopter, dodecarotor.
bool multirotor_type(int type) {
  for (int t : {2, 3, 4, 13, 14, 15, 29}) {
    if (type == t) return true;
  }
  return false;
}

__attribute__((format(printf, 1, 2))) std::string printed(const char* format, ...) {
  char text[300];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  return text;
}

// What a .plan states of its vehicle beside the options: its speed (the
// exposure times' speed, the vehicle's named beside it) unless --speed names
// one, and a note where the mission's speed changes or its vehicle type is
// not the one checked.
std::vector<std::string> plan_vehicle_notes(const PathFile& f, const EnvelopeOptions& given, rt::VehicleEnvelope& e) {
  std::vector<std::string> notes;
  if (f.format != PathFormat::qgc_plan) return notes;
  const bool fixed_wing = e.type == rt::VehicleType::fixed_wing;
  const std::optional<double>& speed = fixed_wing ? f.cruise_speed_m_per_s : f.hover_speed_m_per_s;
  const char* key = fixed_wing ? "cruiseSpeed" : "hoverSpeed";
  if (speed && !given.speed_m_per_s) {
    notes.push_back(printed("speed %.1f m/s: the .plan's %s (the vehicle's %.1f m/s; --speed sets another)", *speed,
                            key, e.speed_m_per_s));
    e.speed_m_per_s = *speed;
  } else if (speed && std::fabs(*speed - e.speed_m_per_s) > 1e-9) {
    notes.push_back(printed("speed %.1f m/s (--speed); the .plan's %s is %.1f m/s", e.speed_m_per_s, key, *speed));
  }
  // the autopilot: --autopilot, else the .plan's firmwareType (it decides
  // whether a multirotor circles a loiter's turns), said where it matters
  const bool stated_ardupilot = f.firmware_type == mavlink::kAutopilotArduPilotMega;
  const bool stated = stated_ardupilot || f.firmware_type == mavlink::kAutopilotPx4;
  const rt::Autopilot file_autopilot = stated_ardupilot ? rt::Autopilot::ardupilot : rt::Autopilot::px4;
  const bool circles_matter = !fixed_wing && std::any_of(f.loiters.begin(), f.loiters.end(), [](const LoiterItem& l) {
    return l.kind == LoiterKind::turns && l.radius_m != 0;
  });
  if (stated && !given.autopilot) {
    if (circles_matter && file_autopilot != e.autopilot) {
      notes.push_back(std::string("autopilot ") + rt::to_string(file_autopilot) +
                      ": the .plan's firmwareType (the vehicle's " + rt::to_string(e.autopilot) +
                      "; --autopilot sets another)");
    }
    e.autopilot = file_autopilot;
  } else if (stated && circles_matter && file_autopilot != e.autopilot) {
    notes.push_back(std::string("autopilot ") + rt::to_string(e.autopilot) +
                    " (--autopilot); the .plan's firmwareType is " + rt::to_string(file_autopilot));
  }
  // the acceptance radius: an autopilot takes a waypoint no later than the
  // mission asks, nor than its own distance (the vehicle's)
  if (f.acceptance_radius_m && *f.acceptance_radius_m > e.acceptance_radius_m) {
    if (!given.acceptance_radius_m) {
      notes.push_back(
          printed("acceptance radius %.0f m: the .plan's waypoints' (param 2; the vehicle's %.0f m; "
                  "--acceptance-radius sets another)",
                  *f.acceptance_radius_m, e.acceptance_radius_m));
      e.acceptance_radius_m = *f.acceptance_radius_m;
    } else {
      notes.push_back(printed("acceptance radius %.0f m (--acceptance-radius); the .plan's waypoints ask for %.0f m",
                              e.acceptance_radius_m, *f.acceptance_radius_m));
    }
  }
  if (f.speed_changes) {
    notes.push_back(
        printed("the mission changes speed (DO_CHANGE_SPEED): times are at %.1f m/s throughout", e.speed_m_per_s));
  }
  const bool plan_multirotor = multirotor_type(f.vehicle_type),
             plan_fixed_wing = f.vehicle_type == mavlink::kTypeFixedWing;
  if ((fixed_wing && plan_multirotor) || (!fixed_wing && plan_fixed_wing)) {
    notes.push_back("the .plan is for a " + std::string(plan_multirotor ? "multirotor" : "fixed-wing") +
                    " (vehicleType " + std::to_string(f.vehicle_type) + "); checked as " + rt::to_string(e.type) +
                    " (--vehicle)");
  }
  return notes;
}

// Altitudes above home are the planned home's: an autopilot measures them
// from where it is armed. The home's altitude against the terrain there.
std::string home_note(const Vec3& home, const fields::Bounds2D& extent, const rt::PathChecker& checker) {
  if (!extent.contains(home.x(), home.y())) {
    return printed("altitudes above home: the planned home (%.1f, %.1f) lies outside the pack, its ground unchecked",
                   home.x(), home.y());
  }
  const double ground = checker.ground_m(home.x(), home.y()), above = home.z() - ground;
  std::string note =
      printed("altitudes above home: the planned home's %.1f m, the terrain there %.1f m", home.z(), ground);
  constexpr double kHomeToleranceM = 5.0;
  if (std::fabs(above) > kHomeToleranceM) {
    note += printed("; armed on that ground, the aircraft flies every waypoint %.1f m ", std::fabs(above));
    note += above > 0 ? "lower than checked" : "higher than checked";
  }
  return note;
}

// Altitudes a path may name (m from the datum): the packs' heights lie
// within +-200 km, and no aircraft flies above 100 km.
constexpr double kMaxAltitudeM = 1e5;

// A .plan's landing approach: the loiter over its last waypoint before the
// landing. The path ends at that waypoint; the circle is flown after it, and
// a circle under the clearance is a requirement unmet, as `plan` writes no
// mission with one (one came 32 m under a hill). Its observers and F_p are
// not judged, nor the landing.
struct Approach {
  std::vector<std::string> notes;
  std::vector<std::string> unmet;
  nlohmann::json circles = nlohmann::json::array();  // {item, radius_m, altitude_m, lowest_clearance_m, met}
};

Approach judge_approach(const PathFile& file, const rt::PathChecker& checker, const fields::VolumeGeometry& g,
                        double clearance_m) {
  Approach out;
  for (const LoiterItem& a : file.approach) {
    const double r = std::fabs(a.radius_m);
    std::string circle =
        a.radius_m != 0 ? printed("a loiter of %.0f m radius", r) : std::string("a loiter of the autopilot's radius");
    circle += printed(" at %.1f m (the DEM's datum)", a.altitude_m);
    nlohmann::json j = {{"item", a.item}, {"radius_m", r}, {"altitude_m", a.altitude_m}};
    if (a.radius_m == 0) {  // the autopilot's parameter: not in the file
      j["lowest_clearance_m"] = nullptr;
      j["met"] = nullptr;
      out.notes.push_back(a.item + ", " + circle + " over the last waypoint, and the landing after it are the " +
                          "landing's approach: its circle's radius is the autopilot's, not in the file: not checked");
      out.circles.push_back(std::move(j));
      continue;
    }
    const rt::Vec3& c = file.points[a.vertex];
    const double least = circle_clearance_m([&](double x, double y) { return checker.ground_m(x, y); }, g, c.x(), c.y(),
                                            a.altitude_m, r);
    const bool met = std::isfinite(least) && least >= clearance_m - kHeightTolM;
    j["lowest_clearance_m"] = std::isfinite(least) ? nlohmann::json(least) : nlohmann::json();
    j["met"] = met;
    out.circles.push_back(std::move(j));
    const std::string lowest = !std::isfinite(least) ? std::string("its circle leaves the terrain the pack knows")
                                                     : printed("its circle at least %.1f m over the ground", least);
    out.notes.push_back(a.item + ", " + circle + " over the last waypoint, and the landing after it are the " +
                        "landing's approach: " + lowest + " (the clearance alone is checked there)");
    if (!std::isfinite(least)) {
      out.unmet.push_back("approach: " + a.item + "'s circle (" + circle +
                          ") leaves the terrain the pack knows: its clearance is unknown");
    } else if (!met) {
      out.unmet.push_back(
          printed("approach: %s's circle (%s) comes to %.1f m over the ground, under the %.1f m "
                  "clearance",
                  a.item.c_str(), circle.c_str(), least, clearance_m));
    }
  }
  return out;
}

int run_check(const CheckOptions& o) {
  Result<PlanningPack> opened = open_planning_pack(o.pack);
  if (!opened.ok()) return fail("check", opened.status());
  const PlanningPack& p = *opened;
  Result<rt::VehicleEnvelope> envelope = resolve_envelope(o.envelope);
  if (!envelope.ok()) return fail("check", envelope.status());
  Result<PathFile> file = read_path_file(o.path, p.pack->metadata().crs_wkt);
  if (!file.ok()) return fail("check", file.status());
  std::vector<std::string> notes = plan_vehicle_notes(*file, o.envelope, *envelope);
  if (!file->has_heights) {
    return fail("check", invalid_argument(o.path + ": the path has no heights (x y z or a file with altitudes)"));
  }
  // no terrain to judge a vertex against beyond the pack (a plan made for
  // another area, or another CRS)
  const fields::Bounds2D extent = storage::post_extent(p.pack->geometry(0));
  for (std::size_t k = 0; k < file->points.size(); ++k) {
    const rt::Vec3& v = file->points[k];
    if (!extent.contains(v.x(), v.y())) {
      char text[400];
      std::snprintf(text, sizeof text,
                    ": vertex %zu (%.1f, %.1f) lies outside the pack (x %.1f..%.1f, y %.1f..%.1f): no terrain to "
                    "judge it on; check it on a pack that covers the mission (visvol build --area)",
                    k, v.x(), v.y(), extent.xmin_m, extent.xmax_m, extent.ymin_m, extent.ymax_m);
      return fail("check", invalid_argument(o.path + text));
    }
    if (!(std::fabs(v.z()) <= kMaxAltitudeM)) {
      char text[200];
      std::snprintf(text, sizeof text, ": vertex %zu altitude %g m is beyond +-%.0f km of the datum", k, v.z(),
                    kMaxAltitudeM / 1000);
      return fail("check", invalid_argument(o.path + text));
    }
  }
  // the path flown: a .plan's loiters as circles
  Result<FlownPath> flown = fly_path(*file, *envelope);
  if (!flown.ok()) return fail("check", flown.status().with_context(o.path));
  for (const rt::Vec3& v : flown->points) {
    if (!extent.contains(v.x(), v.y())) {
      char text[300];
      std::snprintf(text, sizeof text,
                    ": a loiter's circle reaches (%.1f, %.1f), outside the pack (x %.1f..%.1f, y %.1f..%.1f): no "
                    "terrain to judge it on",
                    v.x(), v.y(), extent.xmin_m, extent.xmax_m, extent.ymin_m, extent.ymax_m);
      return fail("check", invalid_argument(o.path + text));
    }
  }
  const std::vector<rt::Vec3>& path = flown->points;
  const rt::FieldForces<storage::PackLevel> field(p.levels.front(), rt::ForceGains{});
  rt::PathCheckSpec spec;
  spec.envelope = *envelope;
  Result<std::vector<rt::ConstraintPoint>> observers = constraint_points(o.constraints);
  if (!observers.ok()) return fail("check", observers.status());
  for (const rt::ConstraintKind kind : {rt::ConstraintKind::hidden_from, rt::ConstraintKind::visible_to}) {
    const auto n = std::count_if(observers->begin(), observers->end(),
                                 [&](const rt::ConstraintPoint& c) { return c.kind == kind; });
    if (n > rt::kMaxPlanObservers) {  // as plan: each point's sight lines are drawn from every sample
      return fail("check", invalid_argument(std::to_string(n) + " --" + rt::to_string(kind) + " points: at most " +
                                            std::to_string(rt::kMaxPlanObservers)));
    }
  }
  spec.constraints = std::move(*observers);
  spec.planning_bounds = p.bounds;
  spec.curvature_coeff = p.curvature_coeff;
  Result<rt::PathChecker> checker = rt::PathChecker::create(rt::level_terrain(p.levels.front()), &field, spec);
  if (!checker.ok()) return fail("check", checker.status());
  if (file->relative_home) notes.push_back(home_note(*file->relative_home, extent, *checker));
  notes.insert(notes.end(), file->notes.begin(), file->notes.end());
  const Approach approach = judge_approach(*file, *checker, p.levels.front().geometry(), spec.envelope.clearance_m);
  notes.insert(notes.end(), approach.notes.begin(), approach.notes.end());
  // samples every sixteenth of a post along the path, a sight line from each to
  // every observer: a path zigzagging across the pack millions of times, or
  // hundreds of observers of a long one, would take hours
  const double samples = checker->sample_count(path);
  const std::size_t observer_count = std::max<std::size_t>(1, spec.constraints.size());
  const double work = samples * static_cast<double>(observer_count);
  if (!(work <= rt::PathChecker::kMaxSamples)) {
    char text[240];
    std::snprintf(text, sizeof text,
                  ": %.3g samples of %.2f m along the path, times %zu observers: more than %.0f to check", samples,
                  checker->spec().sample_step_m, observer_count, rt::PathChecker::kMaxSamples);
    return fail("check", invalid_argument(o.path + text));
  }
  const rt::PathCheck c = checker->check(path.data(), static_cast<int>(path.size()), flown->turn_radius_m.data());
  // the autopilot's lateral track: waypoint legs only (PX4's loiter
  // controller is not modelled)
  std::vector<rt::FlownCheck> flights;
  if (flown->loiters.empty()) {
    flights = checker->fly(path);
  } else if (rt::is_px4_fixed_wing(*envelope) && envelope->acceptance_radius_m > 0) {
    notes.push_back("the PX4 L1 flight is not reported: the mission loiters, which it does not model");
  }
  Holds holds;
  holds.in_sight_s.assign(c.constraints.size(), 0.0);
  for (std::size_t i = 0; i < path.size() && i < c.per_vertex.size(); ++i) {
    const double held_s = flown->hold_s[i];
    holds.total_s += held_s;
    for (std::size_t k = 0; k < c.per_vertex[i].seen_by.size() && k < holds.in_sight_s.size(); ++k)
      if (c.per_vertex[i].seen_by[k]) holds.in_sight_s[k] += held_s;
  }

  if (o.json) {
    nlohmann::json j = check_json(c, *envelope, holds, approach.unmet);
    j["approach"] = approach.circles;
    j["pack"] = o.pack;
    j["path"] = o.path;
    j["per_vertex"] = vertices_json(c, path);
    for (std::size_t i = 0; i < path.size(); ++i) {  // the file's vertex, null on a loiter's circle
      const int v = flown->vertex_of[i];
      j["per_vertex"][i]["file_vertex"] = v >= 0 ? nlohmann::json(v) : nlohmann::json();
    }
    j["loiters"] = flown->loiters;
    j["flown"] = flown_json(flights);
    j["notes"] = notes;
    // the keys plan's summary has: a path checked had no rope run, so both
    // are its own F_c
    j["fc_start"] = c.fc;
    j["fc_end"] = c.fc;
    std::printf("%s\n", json_text(j, 2).c_str());
  } else {
    char held[64] = "";
    if (holds.total_s > 0) std::snprintf(held, sizeof held, " and %.0f s held", holds.total_s);
    std::printf("path       %s: %zu vertices (%zu points flown), %.0f m, %.0f s at %.1f m/s%s (vehicle %s)\n",
                o.path.c_str(), file->points.size(), path.size(), c.length_m, c.duration_s + holds.total_s,
                envelope->speed_m_per_s, held, envelope->name.c_str());
    for (const std::string& n : notes) std::printf("note       %s\n", n.c_str());
    for (const std::string& l : flown->loiters) std::printf("loiter     %s\n", l.c_str());
    std::printf("F_c        %.5f (the field of %s)\n", c.fc, o.pack.c_str());
    print_vertices(c, path, flown->vertex_of);
    print_check(c, *envelope, holds, approach.unmet);
    print_flown(flights, c, *envelope);
  }
  return c.all_met && approach.unmet.empty() ? kExitOk : kExitFailure;
}

}  // namespace

Runner add_check_command(CLI::App& app) {
  auto o = std::make_shared<CheckOptions>();
  CLI::App* c = app.add_subcommand(
      "check", "Assess any path: per vertex F_p, clearance, sight of each observer, climb and turn; totals");
  c->add_option("PACK", o->pack, "Field pack")->required();
  c->add_option("PATH", o->path,
                "The path: a QGroundControl .plan, GeoJSON (RFC 7946), the CSV of visvol plan, or text 'x y z' "
                "(pack CRS, m)")
      ->required();
  add_envelope_options(*c, o->envelope);
  add_constraint_options(*c, o->constraints);
  c->add_flag("--json", o->json, "Print the assessment as one JSON object (per_vertex included)");
  c->footer(
      "Sight lines are Franklin & Ray's R3 on the finest terrain from each observer's eye to samples a sixteenth "
      "of a post apart. Exit status: 0 when every requirement holds, 1 when one does not, 2 for bad arguments or "
      "input.");
  return [o] { return run_check(*o); };
}

}  // namespace visvol::cli
