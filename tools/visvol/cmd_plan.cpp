// visvol plan PACK --from X Y Z --to X Y Z --objective hide|show -o OUT:
// the offline planner (paper, section 4) on a field pack.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "app/mission_options.hpp"
#include "base/tolerances.hpp"
#include "check_report.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "io/json_text.hpp"
#include "pack_planner.hpp"  // the planner and sampler for packs: compiled in visvol_pack_planner
#include "path_io.hpp"
#include "plan_publish.hpp"
#include "planning_pack.hpp"
#include "rt/rope/planner.hpp"
#include "storage/pack_identity.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::cli {

namespace {

using storage::PackLevel;

struct PlanOptions {
  std::string pack, out;
  std::vector<double> from, to;
  std::string objective = "hide", model = "articulated", init = "global";
  int segments = 128;
  EnvelopeOptions envelope;
  ConstraintOptions constraints;
  double k1 = 1.0, k2 = 1.0, stiffness = 1.0, length_weight = 0.0;
  std::optional<double> slack;
  double max_seconds = 40.0;
  bool json = false;
  bool publish = false;
  PublishOptions dds;
};

msg::TerrainInfo terrain_info(const storage::Pack& pack, const std::string& pack_path) {
  msg::TerrainInfo t{};
  t.stamp_ns = msg::now_stamp_ns();
  msg::copy_text(t.pack_id, storage::pack_id_from_path(pack_path));
  msg::copy_text(t.crs, storage::epsg_from_wkt(pack.metadata().crs_wkt));
  if (!msg::copy_text(t.crs_wkt, pack.metadata().crs_wkt)) t.crs_wkt[0] = '\0';  // never a torn WKT
  const fields::VolumeGeometry g = pack.geometry(0);
  t.min = {g.origin_x, g.origin_y - (g.ny - 1) * g.spacing_m, g.z0_m};
  t.max = {g.origin_x + (g.nx - 1) * g.spacing_m, g.origin_y, g.top_m()};
  t.post_spacing_m = g.spacing_m;
  const fields::Bounds2D b = storage::planning_bounds(pack);
  t.planning_min = {b.xmin_m, b.ymin_m, 0.0};
  t.planning_max = {b.xmax_m, b.ymax_m, 0.0};
  return t;
}

// A point read back from a file, or off a printed bound, is out by its
// rounding: where that took it out of the bounds by under a centimetre (the
// check's tolerance), it goes back in.
void into_bounds(rt::Vec3& v, const fields::Bounds2D& b) {
  // the same comparison as the check's, the console's and the DDS codec's
  const bool within = v.x() >= b.xmin_m - kBoundsTolM && v.x() <= b.xmax_m + kBoundsTolM &&
                      v.y() >= b.ymin_m - kBoundsTolM && v.y() <= b.ymax_m + kBoundsTolM;
  if (!within) return;
  v.x() = std::clamp(v.x(), b.xmin_m, b.xmax_m);
  v.y() = std::clamp(v.y(), b.ymin_m, b.ymax_m);
}

std::optional<rt::Vec3> point_of(const std::vector<double>& v) {
  if (v.size() != 3) return std::nullopt;
  return rt::Vec3(v[0], v[1], v[2]);
}

// Each point of an --init path inside the planning bounds and, with heights,
// between the terrain and the field's top; errors name the file and the
// point as the file counts them (1 the first).
// The most points a 2D --init path is lifted to (24 MB of them).
constexpr double kMaxLiftedPoints = 1e6;

Status check_init_points(const std::string& file_name, const PathFile& file, const PlanningPack& p,
                         const fields::FieldSampler<PackLevel>& finest) {
  const fields::Bounds2D& b = p.bounds;
  const double top_m = p.levels.front().geometry().top_m();
  for (std::size_t i = 0; i < file.points.size(); ++i) {
    const rt::Vec3& v = file.points[i];
    std::ostringstream msg;
    msg.precision(1);
    msg << std::fixed << "--init " << file_name << ": point " << i + 1 << " (" << v.x() << ", " << v.y();
    if (file.has_heights) msg << ", " << v.z();
    msg << ") ";
    if (!b.contains(v.x(), v.y())) {
      msg << "is outside the pack's planning bounds (" << storage::describe(b) << ")";
      return invalid_argument(msg.str());
    }
    if (!file.has_heights) continue;
    const double ground_m = finest.height(v.x(), v.y());
    if (v.z() < ground_m) {
      msg << "is " << ground_m - v.z() << " m below the terrain";
      return invalid_argument(msg.str());
    }
    if (v.z() > top_m) {
      msg << "is over the field's top " << top_m << " m";
      return invalid_argument(msg.str());
    }
  }
  // A 2D path is lifted over the terrain every half post: bounded, so that a
  // path zigzagging across the pack cannot ask for gigabytes of points (the
  // rope is laid on 128 segments of it in any case).
  if (!file.has_heights) {
    double length_m = 0;
    for (std::size_t i = 1; i < file.points.size(); ++i) {
      length_m += std::hypot(file.points[i].x() - file.points[i - 1].x(), file.points[i].y() - file.points[i - 1].y());
    }
    const double step_m = p.levels.front().geometry().spacing_m / 2;
    if (length_m / step_m + static_cast<double>(file.points.size()) > kMaxLiftedPoints) {
      std::ostringstream msg;
      msg.precision(1);
      msg << std::fixed << "--init " << file_name << ": " << file.points.size() << " points, " << length_m / 1000
          << " km: lifted over the terrain every " << step_m << " m that is more than " << kMaxLiftedPoints
          << " points; trace a shorter path";
      return invalid_argument(msg.str());
    }
  }
  return Status::ok_status();
}

// The request from the options and the pack: envelope, constraints, bounds.
Result<rt::PlanRequest> plan_request(const PlanOptions& o, const PlanningPack& p) {
  rt::PlanRequest r;
  r.from = *point_of(o.from);
  r.to = *point_of(o.to);
  into_bounds(r.from, p.bounds);
  into_bounds(r.to, p.bounds);
  r.objective = o.objective == "show" ? rt::Objective::show : rt::Objective::hide;
  Result<rt::RopeModel> model = rt::parse_rope_model(o.model.c_str());
  if (!model.ok()) return model.status();
  r.model = *model;
  r.segments = o.segments;
  Result<rt::VehicleEnvelope> envelope = resolve_envelope(o.envelope);
  if (!envelope.ok()) return envelope.status();
  r.envelope = *envelope;
  r.report_flights = true;  // the answer flown as PX4 would, in the summary
  Result<std::vector<rt::ConstraintPoint>> observers = constraint_points(o.constraints);
  if (!observers.ok()) return observers.status();
  r.constraints = std::move(*observers);
  r.planning_bounds = p.bounds;
  r.curvature_coeff = p.curvature_coeff;
  r.visibility_gain = o.k1;
  r.terrain_gain = o.k2;
  r.stiffness = o.stiffness;
  r.slack = o.slack.value_or(-1.0);  // negative: the planner's default
  r.length_weight = o.length_weight;
  r.max_seconds_per_level = o.max_seconds;
  const fields::FieldSampler<PackLevel> finest(p.levels.front());
  if (o.init == "straight") {
    r.init = rt::InitialPath::straight;
  } else if (o.init == "global") {
    r.init = rt::InitialPath::global;
  } else {
    Result<PathFile> file = read_path_file(o.init, p.pack->metadata().crs_wkt);
    if (!file.ok()) return invalid_argument("--init " + file.status().message());
    for (rt::Vec3& v : file->points) into_bounds(v, p.bounds);
    VISVOL_RETURN_IF_ERROR(check_init_points(o.init, *file, p, finest));
    r.init = rt::InitialPath::polyline;
    if (file->has_heights) {
      r.polyline = file->points;
    } else {
      r.polyline = lift_polyline(file->points, r.envelope.clearance_m, p.levels.front().geometry().spacing_m / 2,
                                 [&](double x, double y) { return finest.height(x, y); });
    }
    // The rope runs between --from and --to: they close the traced path.
    r.polyline.insert(r.polyline.begin(), r.from);
    r.polyline.push_back(r.to);
  }
  return r;
}

// An --init file that is one of the plan's own outputs would be overwritten
// (or, where the plan writes only part of its set, removed).
Status check_init_is_no_output(const PlanOptions& o) {
  const std::string init = o.init == "straight" || o.init == "global" ? std::string() : o.init;
  for (const char* extension : {".csv", ".kml", ".plan", ".geojson"}) {
    VISVOL_RETURN_IF_ERROR(output_is_no_input(o.out + extension, std::string("-o's ") + (extension + 1),
                                              {{"--init", init}, {"pack", o.pack}}));
  }
  return Status::ok_status();
}

// A fixed-wing .plan circles over the last vertex at its altitude before it
// lands (path_io.hpp): that circle's least height over the finest terrain;
// NaN for a multirotor, or a turn radius of 0 (the autopilot's own circle).
double landing_loiter_clearance(const fields::FieldSampler<PackLevel>& finest, const fields::VolumeGeometry& g,
                                const rt::VehicleEnvelope& v, const rt::Vec3& end) {
  if (v.type != rt::VehicleType::fixed_wing || !(v.min_turn_radius_m > 0)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return circle_clearance_m([&](double x, double y) { return finest.height(x, y); }, g, end.x(), end.y(), end.z(),
                            v.min_turn_radius_m);
}

// The early descent unmet at the end: an autopilot takes the end's height
// up to its hold distance early (rt::altitude_hold_m), over the ground behind
// the end, and no path to this end clears that. The height that does, for
// the operator (the terrain sampled every metre back along the path, a metre
// over it for what lies between; as far back as the check looks, a sample
// step more than the hold); "" where the end is not the reason (a last leg's
// held stretch is this path's, not every path's: its vertex's early_m says
// where).
std::string low_end_note(const fields::FieldSampler<PackLevel>& finest, double spacing_m, const rt::VehicleEnvelope& v,
                         const std::vector<rt::Vec3>& path, const rt::PathCheck& check) {
  const auto early = std::find_if(check.envelope.begin(), check.envelope.end(),
                                  [](const rt::LimitResult& l) { return l.name == "early-descent"; });
  if (early == check.envelope.end() || early->met || path.size() < 2) return "";
  const double hold_m = rt::altitude_hold_m(v);
  double left_m = hold_m + rt::kSightStepPosts * spacing_m + 1.0, highest_m = -std::numeric_limits<double>::infinity();
  for (std::size_t k = path.size() - 1; k > 0 && left_m > 0; --k) {
    const rt::Vec3 &b = path[k], &a = path[k - 1];
    const double leg_m = std::hypot(b.x() - a.x(), b.y() - a.y());
    for (double back_m = 0; back_m <= std::min(leg_m, left_m); back_m += 1.0) {
      const double u = leg_m > 0 ? back_m / leg_m : 0.0;
      highest_m = std::max(highest_m, finest.height(b.x() + u * (a.x() - b.x()), b.y() + u * (a.y() - b.y())));
    }
    left_m -= leg_m;
  }
  const double needed_m = std::ceil(highest_m + v.clearance_m + 1.0);
  if (!(path.back().z() < needed_m - 1.0)) return "";
  char text[400];
  std::snprintf(text, sizeof text,
                "early-descent: the end at %.1f m is taken %.0f m early, over ground up to %.1f m high on this "
                "path's way to it: an end under %.0f m cannot clear that ground (a plan to a higher end may come "
                "another way: check it again)",
                path.back().z(), hold_m, highest_m, needed_m);
  return text;
}

// PX4's fixed-wing guidance takes a waypoint at its own switch distance when
// that is farther than the mission asks: its L1 controller (PX4 up to 1.13)
// at FW_L1_PERIOD x FW_L1_DAMPING / pi seconds of flight over the ground (20
// x 0.75 / pi by default; NPFG, 1.14 on, nearer). ArduPlane takes the
// mission's radius (param 2).
constexpr double kL1SwitchS = 20.0 * 0.75 / 3.14159265358979323846;
std::string early_switch_note(const rt::VehicleEnvelope& v) {
  const double ground_m_per_s = v.speed_m_per_s + v.max_wind_m_per_s;  // the fastest, with the wind behind
  const double l1_m = kL1SwitchS * ground_m_per_s;
  const double switch_m = rt::switch_distance_m(v);
  if (!rt::is_px4_fixed_wing(v) || !(switch_m < l1_m)) {
    return "";
  }
  char asked[160];
  if (switch_m > 0) {
    std::snprintf(asked, sizeof asked,
                  "takes each waypoint %.0f m early (param 2 asks for %.0f m, at %.0f m/s over the ground)", switch_m,
                  v.acceptance_radius_m, ground_m_per_s);
  } else {
    std::snprintf(asked, sizeof asked, "reaches each waypoint (acceptance radius 0)");
  }
  char text[480];
  std::snprintf(text, sizeof text,
                "the path is checked for an autopilot that %s; PX4's fixed-wing L1 guidance (up to 1.13) switches "
                "%.0f m early at %.0f m/s over the ground by default: give "
                "--acceptance-radius the distance yours does at cruise speed and --max-wind the strongest wind",
                asked, l1_m, ground_m_per_s);
  return text;
}

int run_plan(const PlanOptions& o) {
  if (Status s = check_path_outputs(o.out); !s.ok()) return fail("plan", s.with_context("-o"));
  if (Status s = check_init_is_no_output(o); !s.ok()) return fail("plan", s);
  // checked whether or not --publish is given: a value typed is a value meant
  if (Status s = validate(o.dds); !s.ok()) return fail("plan", s);
  Result<PlanningPack> opened = open_planning_pack(o.pack);
  if (!opened.ok()) return fail("plan", opened.status());
  const PlanningPack& planning = *opened;
  std::vector<const PackLevel*> pointers;
  for (const PackLevel& l : planning.levels) pointers.push_back(&l);
  Result<rt::PlanRequest> request = plan_request(o, planning);
  if (!request.ok()) return fail("plan", request.status());
  const rt::PlanRequest& r = *request;
  const auto& levels = planning.levels;
  const fields::FieldSampler<PackLevel> finest(levels.front());
  const auto& pack = planning.pack;

  std::unique_ptr<PlanPublisher> publisher;
  if (o.publish) {
    const auto probe = [&](const rt::Vec3& v, double& fp, double& clearance_m) {
      fp = finest.visibility(v.x(), v.y(), v.z());
      clearance_m = v.z() - finest.height(v.x(), v.y());
    };
    Result<std::unique_ptr<PlanPublisher>> p =
        PlanPublisher::create(o.dds, terrain_info(*pack, o.pack),
                              r.objective == rt::Objective::show ? msg::Objective::show : msg::Objective::hide, probe);
    if (!p.ok()) return fail("plan", p.status());
    publisher = std::move(*p);
  }

  Progress progress("planning");
  int first_level = -1;  // the rope settles from this level to the finest
  Result<rt::PlanResult> res = rt::plan(pointers, r, [&](const rt::PlanProgress& p) {
    if (first_level < 0) first_level = p.level;
    progress.update(std::min(0.99, p.simulated_s / (o.max_seconds * (first_level + 1))));
    if (publisher) publisher->progress(p.vertices, p.vertex_count, p.fc);
  });
  if (!res.ok()) return fail("plan", res.status());
  progress.finish();
  // the lowest clearance every output names (files, --json, DDS) is the
  // check's, between vertices too (the vertices' alone read higher than the verdict)
  for (const rt::LimitResult& l : res->final_check.envelope) {
    if (l.name == "clearance")
      res->final_metrics.min_clearance_m = std::min(res->final_metrics.min_clearance_m, l.worst);
  }
  Status delivery;
  if (publisher) {
    const auto& limits = res->final_check.envelope;
    const bool inside = std::all_of(limits.begin(), limits.end(), [](const rt::LimitResult& l) { return l.met; });
    delivery = publisher->finish(res->final_path, res->final_metrics, res->converged, inside);
  }

  // per-vertex figures on the finest level
  PathReport report;
  report.vertices = res->final_path;
  report.metrics = res->final_metrics;
  report.objective = rt::to_string(r.objective);
  report.model = rt::to_string(r.model);
  report.pack = o.pack;
  report.crs_wkt = pack->metadata().crs_wkt;
  report.home_ground_m = finest.height(report.vertices.front().x(), report.vertices.front().y());
  report.land_ground_m = finest.height(report.vertices.back().x(), report.vertices.back().y());
  report.vehicle = r.envelope;
  report.requirements_met = res->final_check.all_met;
  report.unmet = res->final_check.unmet();
  report.flyable = res->final_check.flight_violation <= 0;
  report.landing_loiter_clearance_m =
      landing_loiter_clearance(finest, levels.front().geometry(), r.envelope, report.vertices.back());
  for (const rt::Vec3& v : report.vertices) {
    report.per_vertex.push_back({finest.visibility(v.x(), v.y(), v.z()), v.z() - finest.height(v.x(), v.y())});
  }
  std::vector<std::string> written;
  Wgs84Conversion conversion;
  const Status outputs = write_path_outputs(o.out, report, written, &conversion);
  // a crew flies the WGS84 positions: say when they are only metres good
  std::vector<std::string> notes;
  if (std::string note = wgs84_accuracy_note(conversion); !note.empty()) notes.push_back(std::move(note));
  if (std::string note = early_switch_note(r.envelope); !note.empty()) notes.push_back(std::move(note));
  if (std::string note =
          low_end_note(finest, levels.front().geometry().spacing_m, r.envelope, res->final_path, res->final_check);
      !note.empty()) {
    notes.push_back(std::move(note));
  }
  if (r.envelope.type == rt::VehicleType::fixed_wing && !(r.envelope.min_turn_radius_m > 0)) {
    notes.push_back(
        "the .plan's landing circle has the autopilot's own radius (min-turn-radius 0: PX4 80 m, "
        "ArduPlane 60 m by default): not checked against the terrain");
  }

  const rt::PathMetrics& a = res->initial;
  const rt::PathMetrics& b = res->final_metrics;
  const rt::PathCheck& check = res->final_check;
  if (o.json) {
    nlohmann::json j = {{"objective", report.objective},
                        {"model", report.model},
                        {"init", o.init},
                        {"segments", r.segments},
                        {"fc_start", a.fc},
                        {"fc_end", b.fc},
                        {"fc_start_met_all", res->initial_check.all_met},
                        {"length_start_m", a.length_m},
                        {"length_m", b.length_m},
                        {"vertices", res->final_path.size()},
                        {"fitted_vertices", res->fitted_waypoints},
                        {"min_clearance_start_m", a.min_clearance_m},
                        {"min_clearance_m", b.min_clearance_m},
                        {"chosen", res->chosen},
                        {"candidates", res->candidates},
                        {"simulated_s", res->simulated_s},
                        {"equilibrium_s", res->equilibrium_s},
                        {"converged", res->converged},
                        {"diverged", res->diverged},
                        {"wall_s", res->wall_s},
                        {"outputs", written},
                        {"notes", notes}};
    j.update(check_json(check, r.envelope));
    j["flown"] = flown_json(res->final_flown);
    const fields::Bounds2D& box = planning.bounds;
    j["planning_bounds"] = {
        {"xmin_m", box.xmin_m}, {"ymin_m", box.ymin_m}, {"xmax_m", box.xmax_m}, {"ymax_m", box.ymax_m}};
    if (res->has_global) {
      j["fc_global_search"] = res->global.fc;
      j["global_search_level"] = res->global_level;
    }
    if (publisher) {
      j["dds"] = {{"domain", o.dds.domain_id},
                  {"paths_published", publisher->published()},
                  {"publish_errors", publisher->errors()},
                  {"subscribers", publisher->subscribers()},
                  {"nav_msgs_path_subscribers", publisher->path_subscribers()},
                  {"delivered", delivery.ok()}};
    }
    std::printf("%s\n", json_text(j, 2).c_str());
  } else {
    std::printf("%s path, %s rope of %d segments, start: %s, vehicle %s\n", report.objective.c_str(),
                report.model.c_str(), r.segments, o.init.c_str(), r.envelope.name.c_str());
    std::printf("F_c        %.5f at the start -> %.5f (%+.1f%%); the answer is the %s's path (best of %d judged)\n",
                a.fc, b.fc, a.fc > 0 ? 100.0 * (b.fc / a.fc - 1) : 0.0, res->chosen.c_str(), res->candidates);
    if (res->has_global) {
      std::printf("           the global search (level %d) had %.5f\n", res->global_level, res->global.fc);
    }
    std::printf("length     %.0f m, %zu waypoints, %.0f s at %.1f m/s\n", b.length_m, res->final_path.size(),
                check.duration_s, r.envelope.speed_m_per_s);
    if (res->fitted_waypoints > static_cast<int>(res->final_path.size()) && r.thinning) {
      std::printf(
          "           (of %d as fitted: the others lay within %.1f m across and %.1f m up or down of its legs)\n",
          res->fitted_waypoints, r.thinning->horizontal_m, r.thinning->vertical_m);
    }
    std::printf("settled    %s after %.1f simulated s on the finest level (%.1f s over %d levels), %.2f s wall\n",
                res->diverged    ? "NO (the rope diverged; the best path before stands)"
                : res->converged ? "at equilibrium"
                                 : "NOT at equilibrium (time limit)",
                res->equilibrium_s, res->simulated_s, res->first_level + 1, res->wall_s);
    print_check(check, r.envelope);
    print_flown(res->final_flown, check, r.envelope);
    for (const std::string& f : written) std::printf("written    %s\n", f.c_str());
    for (const std::string& n : notes) std::printf("note       %s\n", n.c_str());
    if (publisher) {
      std::printf("published  %llu path updates on DDS domain %u (%llu not sent), %u subscriber(s)%s\n",
                  static_cast<unsigned long long>(publisher->published()), o.dds.domain_id,
                  static_cast<unsigned long long>(publisher->errors()), publisher->subscribers(),
                  delivery.ok() ? "" : ", last path not acknowledged");
    }
  }
  if (!delivery.ok()) return fail("plan", delivery);
  // an output not written is said first, then what the path does not meet
  const int status = outputs.ok() ? kExitOk : fail("plan", outputs);
  if (!check.all_met) {
    std::fprintf(stderr, "visvol plan: the path does not meet every requirement (%s):\n",
                 written.empty() ? "no file written" : "the CSV, KML and GeoJSON written say so");
    for (const std::string& u : check.unmet()) std::fprintf(stderr, "  %s\n", u.c_str());
    return std::max(status, static_cast<int>(kExitFailure));
  }
  return status;
}

}  // namespace

Runner add_plan_command(CLI::App& app) {
  auto o = std::make_shared<PlanOptions>();
  CLI::App* c =
      app.add_subcommand("plan", "Settle a force-directed rope from A to B in a pack's field and write the path");
  c->add_option("PACK", o->pack, "Field pack")->required();
  c->add_option("--from", o->from, "Start X Y Z (pack CRS, m; Z above the DEM's datum)")->expected(3)->required();
  c->add_option("--to", o->to, "End X Y Z")->expected(3)->required();
  c->add_option("--objective", o->objective, "hide (least seen) or show (most seen)")
      ->check(CLI::IsMember({"hide", "show"}))
      ->required();
  c->add_option("--model", o->model, "articulated (inextensible capsules) or spring (spring-mass)")
      ->check(CLI::IsMember({"articulated", "spring"}))
      ->capture_default_str();
  c->add_option("--segments", o->segments,
                "Rope segments (2..4096; with --max-seconds at most 4e7 vertex steps a level: "
                "(segments + 1) x seconds / 1 ms)")
      ->capture_default_str();
  c->add_option("--init", o->init,
                "straight, global (graph search inside the envelope and constraints, coarsest level "
                "first), or a path file (text 'x y' lifted to the clearance or 'x y z', plan CSV, GeoJSON)")
      ->capture_default_str();
  add_envelope_options(*c, o->envelope);
  add_constraint_options(*c, o->constraints);
  c->add_option("--k1", o->k1, "Visibility gain (its sign comes from the objective)")->capture_default_str();
  c->add_option("--k2", o->k2, "Terrain force field gain")->capture_default_str();
  c->add_option("--stiffness", o->stiffness, "Rope stiffness factor")->capture_default_str();
  c->add_option("--slack", o->slack,
                "Articulated rope: extra length over the initial path, 0..10 (default 0.3 straight, 0.05 "
                "otherwise)")
      ->check(CLI::Range(0.0, 10.0));
  c->add_option("--length-weight", o->length_weight, "Global search: cost per metre on top of F_p")
      ->capture_default_str();
  c->add_option("--max-seconds", o->max_seconds,
                "Simulated seconds per level of detail at most (not wall time: a level of 4e7 vertex "
                "steps, the most --segments allow, takes about half a minute)")
      ->capture_default_str();
  c->add_option("-o,--output", o->out, "Output base name: writes BASE.geojson, .csv, .kml, .plan")->required();
  c->footer(
      "Exit status: 0 when the path meets every requirement (constraints, envelope, planning bounds: "
      "checked with exact sight lines on the finest terrain), 1 when one is unmet (the path is still "
      "written and marked unmet; a path that breaks the envelope or leaves the planning bounds, or whose "
      "fixed-wing landing circle comes under the clearance, gets no .plan) "
      "or planning failed, 2 for bad arguments or input.");
  c->add_flag("--json", o->json, "Print the summary as one JSON object");
  c->add_flag("--publish", o->publish,
              "Publish the path on DDS (the console's path topics) while it settles and when done");
  c->add_option("--domain", o->dds.domain_id, "DDS domain id for --publish")
      ->check(CLI::Range(0u, dds::kMaxDomainId))
      ->capture_default_str();
  c->add_option("--dds-config", o->dds.cyclone_config_path,
                "Cyclone DDS XML configuration for --publish (default: loopback only)")
      ->check(CLI::ExistingFile);
  c->add_option("--namespace", o->dds.topic_namespace, "Topic namespace for --publish (ROS style)");
  c->add_option("--publish-hz", o->dds.rate_hz, "Path updates per second at most while settling")
      ->capture_default_str();
  c->add_option("--linger", o->dds.linger_s, "Seconds to wait at the end for subscribers to acknowledge the last path")
      ->capture_default_str();
  return [o] { return run_plan(*o); };
}

}  // namespace visvol::cli
