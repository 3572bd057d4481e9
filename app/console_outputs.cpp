// The console's outputs: the final path fitted and checked, and the files
// written at the end of a session (path.csv, summary.json, health.csv).
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "app/console_impl.hpp"
#include "app/log.hpp"
#include "io/atomic_file.hpp"
#include "io/json_text.hpp"
#include "rt/rope/check_json.hpp"
#include "rt/rope/path_check.hpp"
#include "rt/rope/waypoint_thinning.hpp"
#include "storage/pack_identity.hpp"

namespace visvol::app {

namespace {

// The observers of a built set, as the planner names them.
std::vector<rt::ConstraintPoint> observers_of(const rt::HullSet* set) {
  std::vector<rt::ConstraintPoint> out;
  if (set == nullptr) return out;
  const rt::HullRequest& r = set->request;
  for (int k = 0; k < r.hidden_count; ++k) {
    out.push_back({rt::ConstraintKind::hidden_from, rt::HullRequest::point(r.hidden_from_m[k]), r.eye_height_m});
  }
  for (int k = 0; k < r.visible_count; ++k) {
    out.push_back({rt::ConstraintKind::visible_to, rt::HullRequest::point(r.visible_to_m[k]), r.eye_height_m});
  }
  return out;
}

// The constraints in force at the end (clearance, ceiling, observers), and
// the hull builder's counts: sets built, refused and put in force.
nlohmann::json constraints_json(const rt::Executive& e, const rt::ConstraintHulls* hulls,
                                const rt::ExecutiveCounters& c) {
  const rt::ForceGains& g = e.forces().gains();
  nlohmann::json j = {{"clearance_m", g.clearance_m},
                      {"max_agl_m", rt::finite_or_null(g.max_agl_m)},
                      {"max_altitude_m", rt::finite_or_null(g.max_altitude_m)},
                      {"eye_height_m", e.config().eye_height_m},
                      {"hidden_from", nlohmann::json::array()},
                      {"visible_to", nlohmann::json::array()},
                      {"hull_builder", hulls != nullptr}};
  for (const rt::ConstraintPoint& p : observers_of(e.hulls_in_force())) {
    j[p.kind == rt::ConstraintKind::hidden_from ? "hidden_from" : "visible_to"].push_back(rt::point_json(p.point_m));
  }
  if (hulls == nullptr) return j;
  const rt::HullStats s = hulls->stats();
  j["max_observers"] = hulls->max_observers();
  j["pending"] = e.hulls_pending();  // a newer set asked for was not built in time
  j["built"] = s.built;
  j["refused"] = s.failed;
  j["sets_in_force"] = c.hull_sets;
  j["last_build_ms"] = s.last_build_ms;
  j["last_error"] = s.last_error;
  return j;
}

// build.curvature_coeff of the pack's metadata (0: none recorded).
double pack_curvature(const storage::Pack& pack) {
  const nlohmann::json meta = nlohmann::json::parse(pack.metadata().json, nullptr, false);
  if (!meta.is_object() || !meta.contains("build") || !meta["build"].is_object()) return 0.0;
  const nlohmann::json& c = meta["build"].value("curvature_coeff", nlohmann::json(0.0));
  return c.is_number() && c.get<double>() >= 0 && c.get<double>() <= 1 ? c.get<double>() : 0.0;
}

// The check's members: per constraint and per envelope limit, and whether
// all are met.
nlohmann::json check_json(const rt::PathCheck& c, double sample_step_m) {
  nlohmann::json j = {{"path", "flyable (the rope's final path fitted into the envelope)"},
                      {"terrain", "level 0 (finest), exact sight lines (R3)"},
                      {"sample_step_m", sample_step_m},
                      {"length_m", c.length_m},
                      {"constraints", nlohmann::json::array()},
                      {"envelope", nlohmann::json::array()},
                      {"inside_planning_bounds", c.inside_planning_bounds},
                      {"inside_bounds_fraction", c.inside_bounds_fraction},
                      {"all_met", c.all_met},
                      {"unmet", c.unmet()}};
  for (const rt::ConstraintResult& r : c.constraints) j["constraints"].push_back(rt::constraint_json(r));
  for (const rt::LimitResult& l : c.envelope) j["envelope"].push_back(rt::limit_json(l));
  return j;
}

// The flyable path's figures, and how many paths were sent.
nlohmann::json flyable_json(const msg::PathSample& p, std::size_t fitted_vertices, bool inside_envelope,
                            const FlyableStats& sent) {
  return {{"vertices", p.vertex_count},
          {"fitted_vertices", fitted_vertices},
          {"fc", p.f_c},
          {"length_m", p.length_m},
          {"min_clearance_m", p.min_clearance_m},
          {"inside_envelope", inside_envelope},
          {"sent", sent.fitted},
          {"sent_outside_envelope", sent.unflyable},
          {"fits_failed", sent.failed},
          {"observers_left_out", sent.hull_failures}};
}

}  // namespace

// The rope where it ended, fitted into the envelope in force: the path the
// outputs give and the check judges (the fitter's thread has stopped).
void Console::Impl::fit_final_path() {
  const rt::Rope& rope = exec->rope();
  PathFitter& fit = flyable ? flyable->fitter() : *fitter;
  const rt::HullSet* set = exec->hulls_in_force();
  fit.set_observers(set != nullptr ? set->request : rt::HullRequest{});
  const rt::EnvelopeFit f = fit.fit(rope.vertices(), rope.segments() + 1, exec->forces().gains());
  final_path = f.path;
  final_fitted_vertices = final_path.size();
  final_flyable = f.feasible;
}

// The judge of the final path: exact sight lines on the finest terrain, the
// envelope and the observers in force, after the loop stopped.
Result<rt::PathChecker> Console::Impl::final_checker() const {
  rt::PathCheckSpec spec;
  spec.envelope = path_fitter().envelope(exec->forces().gains());
  spec.constraints = observers_of(exec->hulls_in_force());
  spec.curvature_coeff = pack_curvature(*pack);
  spec.planning_bounds = bounds;
  return rt::PathChecker::create(path_fitter().terrain(), nullptr, spec);
}

// The final path judged, its waypoints thinned as `visvol plan` thins its
// answer's (rt::thinned_as_good): where that meets as much and costs F_c
// under a thousandth. The fit's splits left runs of vertices on one line.
rt::PathCheck Console::Impl::judge_final_path(const rt::PathChecker& checker) {
  rt::PathCheck fitted = checker.check(final_path);
  if (final_path.size() <= 2) return fitted;
  std::optional<rt::ThinnedPath> thinned = rt::thinned_as_good(final_path, fitted, checker, exec->config().objective);
  if (!thinned) return fitted;
  final_path = std::move(thinned->path);
  return std::move(thinned->check);
}

// The final (flyable) path's verdict, `judged` by `checker` (nothing where
// it could not be); `line` gets it for the operator.
nlohmann::json Console::Impl::check_path(const Result<rt::PathChecker>& checker,
                                         const std::optional<rt::PathCheck>& judged, std::string& line) const {
  if (!checker.ok()) {
    line = "check: " + checker.status().message();
    return {{"error", checker.status().message()}};
  }
  if (!judged) {
    line = "check: no path";
    return {{"error", "no path"}};
  }
  const rt::PathCheck& c = *judged;
  std::vector<std::string> unmet = c.unmet();
  // a spooled rope whose free end has not arrived is no route to the end
  // (a session that ended mid-drag: every other figure met, 760 m short)
  const rt::ExecutiveCounters& k = exec->counters();
  const bool reaches_end = k.mode != msg::InteractionMode::spool || k.spool_arrived;
  if (!reaches_end) {
    char gap[160];
    std::snprintf(gap, sizeof gap, "end: the path stops %.1f m short of it (the spooled rope had not arrived)",
                  k.spool_gap_m);
    unmet.insert(unmet.begin(), gap);
  }
  const bool all_met = c.all_met && reaches_end;
  line = all_met ? "all met" : "NOT MET:";
  for (const std::string& u : unmet) line += " " + u + ";";
  nlohmann::json j = check_json(c, checker->spec().sample_step_m);
  j["reaches_end"] = reaches_end;
  j["all_met"] = all_met;
  j["unmet"] = unmet;
  return j;
}

// A session that ends in a terrain switch keeps its outputs apart, in
// OUT/session-N-PACKID; the last session's are in OUT itself.
std::string Console::Impl::out_dir() const {
  return switch_to.empty() ? o.out : o.out + "/session-" + std::to_string(o.session) + "-" + pack_id;
}

// The outputs of a session: the flyable path (path.csv), the loop's health
// (health.csv), the last thumbnail, and summary.json; then a summary on
// standard output. Each file is written whole or not at all.
Status Console::Impl::write_outputs(const rt::LoopRun& run, double wall_s) {
  const std::string out = out_dir();
  VISVOL_RETURN_IF_ERROR(make_output_dirs(out));
  fit_final_path();
  const Result<rt::PathChecker> checker = final_checker();
  std::optional<rt::PathCheck> judged;
  if (checker.ok() && final_path.size() >= 2) judged = judge_final_path(*checker);
  auto flyable_sample = std::make_unique<msg::PathSample>();
  if (!path_fitter().describe(final_path, *flyable_sample)) {
    log_printf(LogLevel::warning, "visvol-console: warning: the final path's F_p is unknown (NaN): %s\n",
               printable(path_fitter().read_error()).c_str());
  }
  const msg::PathSample& fp = *flyable_sample;
  std::string verdict;
  const nlohmann::json check = check_path(checker, judged, verdict);
  VISVOL_RETURN_IF_ERROR(write_file_atomically(out + "/path.csv", path_csv(fp, check)));
  std::string health_csv =
      "t_s,wake_p99_us,wake_max_us,compute_p99_us,compute_max_us,overruns,misses,fc,converged,device,"
      "resident_tiles_mib,rss_mib,fallbacks\n";
  for (const std::string& line : health_lines) health_csv += line;
  VISVOL_RETURN_IF_ERROR(write_file_atomically(out + "/health.csv", health_csv));
  if (thumbs) {
    const Status t = thumbs->write_last(out + "/thumbnail.png");
    if (!t.ok()) log_printf(LogLevel::warning, "visvol-console: warning: %s\n", t.message().c_str());
  }
  VISVOL_RETURN_IF_ERROR(
      write_file_atomically(out + "/summary.json", json_text(summary_json(run, wall_s, fp, check), 2) + "\n"));
  print_summary(run, wall_s, fp, verdict, out);
  return {};
}

Status Console::Impl::make_output_dirs(const std::string& out) const {
  std::error_code ignored;                              // what went wrong is seen below
  std::filesystem::create_directories(o.out, ignored);  // with its parents (the default is out/console)
  for (const std::string& dir : {o.out, out}) {
    ::mkdir(dir.c_str(), 0755);
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
      return Status(Errc::io, dir + ": cannot create the output directory");
    }
  }
  return {};
}

std::string Console::Impl::path_csv(const msg::PathSample& fp, const nlohmann::json& check) const {
  // what the path is and whether it holds, as the plan CSV says it (a path
  // 760 m short of its end was a bare table): '#' lines, no commas in them
  auto cell = [](std::string text) {
    std::replace(text.begin(), text.end(), ',', ';');
    return text;
  };
  std::string csv = "# visvol-console path: the rope where the session ended, fitted into the envelope\n";
  csv += "# x_m y_m: the pack's CRS (" + cell(storage::epsg_from_wkt(pack->metadata().crs_wkt)) + ") in metres\n";
  csv += "# z_m: height above the DEM's vertical datum (m); fp: F_p; clearance_m: height above the terrain (m)\n";
  const auto all_met = check.find("all_met");
  const bool met = all_met != check.end() && all_met->is_boolean() && all_met->get<bool>();
  csv += std::string("# requirements: ") + (met ? "all met" : "NOT MET") + "\n";
  if (check.contains("unmet") && check["unmet"].is_array()) {
    for (const nlohmann::json& u : check["unmet"]) {
      if (u.is_string()) csv += "#   unmet: " + cell(u.get<std::string>()) + "\n";
    }
  }
  if (check.contains("error") && check["error"].is_string()) {
    csv += "#   not checked: " + cell(check["error"].get<std::string>()) + "\n";
  }
  csv += "x_m,y_m,z_m,fp,clearance_m\n";
  char line[192];
  for (std::uint32_t i = 0; i < fp.vertex_count; ++i) {
    const msg::PathVertex& v = fp.vertices[i];
    std::snprintf(line, sizeof line, "%.3f,%.3f,%.3f,%.6f,%.2f\n", v.position.x_m, v.position.y_m, v.position.z_m,
                  v.visibility, v.clearance_m);
    csv += line;
  }
  return csv;
}

nlohmann::json Console::Impl::summary_json(const rt::LoopRun& run, double wall_s, const msg::PathSample& fp,
                                           const nlohmann::json& check) const {
  const rt::Rope& rope = exec->rope();
  const rt::ExecutiveCounters& c = exec->counters();
  const storage::ResidentStats ts = field->stats();
  auto timing = [](const rt::DurationHistogram& h) {
    return nlohmann::json{
        {"p50_us", h.percentile_us(0.5)}, {"p99_us", h.percentile_us(0.99)}, {"p999_us", h.percentile_us(0.999)},
        {"max_us", h.max_us()},           {"mean_us", h.mean_us()},          {"count", h.count()}};
  };
  nlohmann::json budget_items = nlohmann::json::array();
  for (const rt::MemoryBudget::Item& i : budget.items()) {
    budget_items.push_back({{"what", i.what}, {"mib", static_cast<double>(i.bytes) / kMiB}});
  }
  nlohmann::json j = {
      {"pack", o.pack},
      {"pack_id", pack_id},
      {"session", o.session},
      {"switched_from", o.switched_from},
      {"switched_to", switch_to},
      {"switch_failed", o.switch_failed},
      {"catalogue", catalogue_json()},
      {"wall_s", wall_s},
      {"loop",
       {{"period_us", o.period_us},
        {"ticks", run.totals.ticks},
        {"wake_latency", timing(run.wake_latency)},
        {"compute", timing(run.compute)},
        {"overruns", run.totals.overruns},
        {"misses", run.totals.misses},
        {"safe_states", run.totals.safe_states},
        {"minor_faults_after_settle", run.totals.faults_after_settle.minor},
        {"major_faults_after_settle", run.totals.faults_after_settle.major},
        {"sched_fifo", run.realtime.fifo},
        {"pinned", run.realtime.pinned},
        {"memory_locked", realtime.memory_locked},
        {"warnings", realtime.warnings}}},
      {"path",
       {{"objective", o.objective},
        {"model", rt::to_string(rope.model())},
        {"segments", rope.segments()},
        {"fc_start", fc_start},
        {"fc_end", c.fc},
        {"length_m", rope.length_m()},
        {"converged", c.converged},
        {"equilibrium_s", c.equilibrium_s},
        {"runs", c.runs},
        {"rope_resets", c.rope_resets},
        {"flyable",
         flyable_json(fp, final_fitted_vertices, final_flyable, flyable ? flyable->stats() : FlyableStats{})}}},
      {"vehicle", rt::vehicle_json(vehicle)},
      {"mode", msg::to_string(c.mode)},
      {"mode_switches", c.mode_switches},
      {"mode_refusals", c.mode_refusals},
      {"spool",
       {{"paid_out_m", c.spool_paid_out_m},
        {"segments", c.spool_segments},
        {"gap_m", c.spool_gap_m},
        {"arrived", c.spool_arrived},
        {"at_capacity", c.spool_at_capacity}}},
      {"device",
       {{"kind", o.device}, {"state", device_text(c)}, {"grasps", c.grasps}, {"send_failures", c.send_failures}}},
      {"commands", {{"applied", c.commands_applied}, {"failed", c.commands_failed}}},
      {"constraints", constraints_json(*exec, hulls.get(), c)},
      {"check", check},
      {"memory",
       {{"budget_mib", o.budget_mib},
        {"rss_peak_mib", static_cast<double>(rss_peak) / kMiB},
        {"over_budget", static_cast<double>(rss_peak) > o.budget_mib * kMiB},
        {"rss_end_mib", static_cast<double>(rt::resident_bytes()) / kMiB},
        {"reserved", budget_items}}},
      {"tiles",
       {{"budget_mib", static_cast<double>(ts.budget_bytes) / kMiB},
        {"resident_mib", static_cast<double>(ts.resident_bytes) / kMiB},
        {"pack_mib", static_cast<double>(ts.pack_bytes) / kMiB},
        {"loaded", ts.bricks_loaded},
        {"evicted", ts.bricks_evicted},
        {"corrupt", ts.corrupt_bricks},
        {"lock_failures", ts.lock_failures},
        {"last_error", ts.last_error},
        {"fallbacks", field->fallbacks()}}}};
  if (sim) {
    const hapticsim::SimCounters& sc = sim->device().counters();
    j["device"]["simulated"] = {{"max_force_n", sc.max_force_n},
                                {"watchdog_trips", sc.watchdog_trips},
                                {"last_command_n", sc.last_command_n},
                                {"last_command_enabled", sc.last_command_enabled}};
  }
  if (publisher) {
    const dds::PublisherStats ps = publisher->stats();
    j["dds"] = {{"domain", o.domain},
                {"paths", ps.paths},
                {"health", ps.health},
                {"thumbnails", ps.thumbnails},
                {"errors", ps.errors}};
  }
  if (intake) {
    // commands.applied and .failed are the executive's; the intake's own
    // counts (rejected includes rate_limited and queue_full)
    const dds::CommandCounts& ic = intake->stats().commands;
    j["commands"]["intake"] = {{"received", ic.received},
                               {"accepted", ic.accepted},
                               {"rejected", ic.rejected},
                               {"rate_limited", ic.rate_limited},
                               {"queue_full", ic.queue_full}};
  }
  if (thumbs) {
    const ThumbnailStats t = thumbs->stats();
    j["thumbnails"] = {
        {"view", o.thumbnail_view}, {"size", o.thumbnail_size},           {"rendered", t.rendered},
        {"failed", t.failed},       {"last_render_ms", t.last_render_ms}, {"gl_renderer", thumbs->scene().gl_renderer}};
  }
  return j;
}

void Console::Impl::print_summary(const rt::LoopRun& run, double wall_s, const msg::PathSample& fp,
                                  const std::string& verdict, const std::string& out) const {
  const rt::ExecutiveCounters& c = exec->counters();
  const storage::ResidentStats ts = field->stats();
  const double lowest = fp.min_clearance_m;
  std::printf(
      "visvol-console: %.1f s, %llu ticks; wake-up p50 %.0f us p99 %.0f us max %.0f us; compute p50 %.0f us "
      "p99 %.0f us; overruns %llu; major faults %lld\n",
      wall_s, static_cast<unsigned long long>(run.totals.ticks), run.wake_latency.percentile_us(0.5),
      run.wake_latency.percentile_us(0.99), run.wake_latency.max_us(), run.compute.percentile_us(0.5),
      run.compute.percentile_us(0.99), static_cast<unsigned long long>(run.totals.overruns),
      static_cast<long long>(run.totals.faults_after_settle.major));
  std::printf(
      "path: %s, rope F_c %.4f -> %.4f, %s; flyable (%s): F_c %.4f, %.0f m, %u vertices (of %zu as fitted), "
      "lowest clearance %.1f m, %s; device %s, %llu grasp(s)\n",
      o.objective.c_str(), fc_start, c.fc, c.converged ? "at rest" : "moving", vehicle.name.c_str(), fp.f_c,
      fp.length_m, fp.vertex_count, final_fitted_vertices, lowest,
      final_flyable ? "inside the envelope" : "NOT inside the envelope", device_text(c),
      static_cast<unsigned long long>(c.grasps));
  std::printf("memory: peak RSS %.1f MiB of a %.0f MiB budget; tiles %.1f of %.1f MiB (pack %.1f MiB)\n",
              static_cast<double>(rss_peak) / kMiB, o.budget_mib, static_cast<double>(ts.resident_bytes) / kMiB,
              static_cast<double>(ts.budget_bytes) / kMiB, static_cast<double>(ts.pack_bytes) / kMiB);
  const rt::ForceGains& g = exec->forces().gains();
  const rt::HullSet* set = exec->hulls_in_force();
  auto limit = [](double v) { return std::isfinite(v) ? std::to_string(std::lround(v)) + " m" : std::string("none"); };
  std::printf("constraints: clearance %s, max-agl %s, max-altitude %s, %d hidden-from, %d visible-to%s; %s\n",
              limit(g.clearance_m).c_str(), limit(g.max_agl_m).c_str(), limit(g.max_altitude_m).c_str(),
              set ? set->hidden_count() : 0, set ? set->visible_count() : 0,
              exec->hulls_pending() ? " (a newer set not built yet)" : "", verdict.c_str());
  if (thumbs) {
    const ThumbnailStats t = thumbs->stats();
    std::printf("thumbnails: %llu %s %s (last %.0f ms to render and encode), %llu failed\n",
                static_cast<unsigned long long>(t.rendered), o.thumbnail_view.c_str(), o.thumbnail_size.c_str(),
                t.last_render_ms, static_cast<unsigned long long>(t.failed));
  }
  std::printf("outputs: %s/path.csv, %s/health.csv, %s/summary.json%s\n", out.c_str(), out.c_str(), out.c_str(),
              thumbs ? (", " + out + "/thumbnail.png").c_str() : "");
}

}  // namespace visvol::app
