// visvol-fieldbench: how fast and how big the visibility field build is.
//
// Builds F_p for a 512 x 512 real DEM with 128 levels at cube ranges 32, 64 and
// 128 posts (each run in a child process so its peak RSS is its own), prints the
// median wall time, hull cells per second per core and peak RSS; times the
// fast build against the exact R3 reference on a small grid; and times one
// viewshed against GRASS r.viewshed on the same DEM, observer and radius, run
// side by side in the same invocation.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "base/cli_numbers.hpp"
#include "base/version.hpp"
#include "fields/exact_visibility.hpp"
#include "fields/gdal/dem_import.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/viewshed.hpp"
#include "fields/visibility_builder.hpp"
#include "storage/pack_build.hpp"

namespace {

using namespace visvol;
using namespace visvol::fields;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct RunResult {
  double wall_s = 0, hull_s = 0, scatter_s = 0, cells_per_s_per_core = 0;
  double cells = 0;
  int threads = 0;
  int ok = 0;
};

struct Measured {
  RunResult run;
  double peak_rss_mib = 0;
};

// Runs one build in a child process; its peak RSS comes back through wait4.
Measured measure_build(const Heightfield& hf, const FieldParams& p) {
  int fds[2];
  Measured m;
  if (pipe(fds) != 0) return m;
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    RunResult r;
    BuildStats stats;
    const Result<DenseVolume> f = build_visibility_dense(hf, p, {}, &stats);
    r.ok = f.ok() ? 1 : 0;
    r.wall_s = stats.wall_s;
    r.hull_s = stats.hull_s;
    r.scatter_s = stats.scatter_s;
    r.cells = static_cast<double>(stats.hull_cells);
    r.cells_per_s_per_core = stats.cells_per_s_per_core();
    r.threads = stats.threads;
    if (write(fds[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) _exit(3);
    _exit(r.ok ? 0 : 1);
  }
  close(fds[1]);
  const ssize_t got = read(fds[0], &m.run, sizeof m.run);
  close(fds[0]);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  if (got != static_cast<ssize_t>(sizeof m.run)) m.run.ok = 0;
  m.peak_rss_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is KiB
  return m;
}

struct RangeFigures {
  int range = 0;
  double wall_s = 0, hull_s = 0, scatter_s = 0, mcells = 0, rss_mib = 0, cells = 0;
  int threads = 0;
  bool ok = false;
};

RangeFigures bench_range(const Heightfield& hf, int range, int repeat, int threads) {
  FieldParams p;
  p.nz = 128;
  p.range_shape = RangeShape::cube;
  p.range_posts = range;
  p.threads = threads;
  std::vector<double> wall, hull, scatter, mc, rss;
  RangeFigures f;
  f.range = range;
  f.ok = true;
  for (int n = 0; n < repeat; ++n) {
    const Measured m = measure_build(hf, p);
    f.ok = f.ok && m.run.ok;
    wall.push_back(m.run.wall_s);
    hull.push_back(m.run.hull_s);
    scatter.push_back(m.run.scatter_s);
    mc.push_back(m.run.cells_per_s_per_core / 1e6);
    rss.push_back(m.peak_rss_mib);
    f.cells = m.run.cells;
    f.threads = m.run.threads;
  }
  f.wall_s = median(wall);
  f.hull_s = median(hull);
  f.scatter_s = median(scatter);
  f.mcells = median(mc);
  f.rss_mib = median(rss);
  return f;
}

Heightfield crop(const Heightfield& src, int i0, int j0, int n) {
  Heightfield hf;
  hf.nx = hf.ny = n;
  hf.spacing_m = src.spacing_m;
  hf.origin_x = src.x_of(i0);
  hf.origin_y = src.y_of(j0);
  hf.crs_wkt = src.crs_wkt;
  hf.height_m.resize(hf.size());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) hf.at(i, j) = src.at(i0 + i, j0 + j);
  return hf;
}

struct ExactFigures {
  int n = 48, nz = 32, range = 12;
  double fast_s = 0, exact_s = 0, within = 0;
};

// The fast build against evaluating the exact definition at every voxel.
ExactFigures bench_exact(const Heightfield& dem) {
  ExactFigures e;
  const Heightfield hf = crop(dem, dem.nx / 2 - e.n / 2, dem.ny / 2 - e.n / 2, e.n);
  FieldParams p;
  p.nz = e.nz;
  p.range_posts = e.range;
  p.threads = 1;
  auto t0 = Clock::now();
  const Result<DenseVolume> f = build_visibility_dense(hf, p);
  e.fast_s = seconds_since(t0);
  if (!f.ok()) return e;
  const std::vector<float> area = area_factor(hf);
  const VolumeGeometry& g = f->geometry;
  std::size_t inside = 0, counted = 0;
  t0 = Clock::now();
  for (int k = 0; k < g.nz; ++k) {
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        const double z = g.z_of(k);
        const double v = exact_visibility(hf, area, p, i, j, z);
        if (z < hf.at(i, j) + g.dz_m) continue;
        // The accuracy criterion: between the exact values a level below and above.
        const double lo = std::min(
            {exact_visibility(hf, area, p, i, j, z - g.dz_m), v, exact_visibility(hf, area, p, i, j, z + g.dz_m)});
        const double hi = std::max(
            {exact_visibility(hf, area, p, i, j, z - g.dz_m), v, exact_visibility(hf, area, p, i, j, z + g.dz_m)});
        ++counted;
        inside += f->at(i, j, k) >= lo - 0.005 && f->at(i, j, k) <= hi + 0.005;
      }
    }
  }
  // Three exact evaluations per counted voxel; report the time of one pass.
  e.exact_s = seconds_since(t0) / 3.0;
  e.within = counted ? double(inside) / double(counted) : 0.0;
  return e;
}

struct ViewshedFigures {
  double ours_s = 0, grass_s = -1, agreement = -1;
  std::size_t ours_visible = 0, grass_visible = 0, compared = 0;
  std::string grass_note;
};

// Times r.viewshed inside a throw-away GRASS location and reads its output.
bool run_grass(const std::string& dem, double x, double y, const ViewshedParams& p, const std::string& out_tif,
               double& seconds, std::string& note) {
  if (std::system("command -v grass >/dev/null 2>&1") != 0) {
    note = "grass not installed (Debian package grass-core)";
    return false;
  }
  char dir_template[] = "/tmp/visvol-grass-XXXXXX";
  const char* dir = mkdtemp(dir_template);
  if (!dir) return false;
  const std::string script = std::string(dir) + "/run.sh";
  const std::string timing = std::string(dir) + "/time.txt";
  std::ofstream(script) << "set -e\n"
                        << "r.in.gdal -o input='" << dem << "' output=dem --quiet\n"
                        << "g.region raster=dem\n"
                        << "TIMEFORMAT=%R\n"
                        << "{ time r.viewshed input=dem output=vs coordinates=" << std::fixed << x << "," << y
                        << " observer_elevation=" << p.observer_height_m << " target_elevation=" << p.target_height_m
                        << " max_distance=" << p.max_distance_m << " --quiet ; } 2> '" << timing << "'\n"
                        << "r.out.gdal input=vs output='" << out_tif << "' format=GTiff type=Float32 --quiet -c\n";
  const std::string log = std::string(dir) + "/grass.log";
  const std::string cmd = "grass --tmp-location '" + dem + "' --exec bash '" + script + "' >'" + log + "' 2>&1";
  const bool ok = std::system(cmd.c_str()) == 0;
  if (ok) std::ifstream(timing) >> seconds;
  if (!ok) {
    // Keep the last line GRASS printed: it says why.
    std::ifstream in(log);
    std::string line, last;
    while (std::getline(in, line)) {
      if (!line.empty()) last = line;
    }
    note = "r.viewshed failed: " + last;
  }
  for (const std::string& f : {script, timing, log}) std::remove(f.c_str());
  rmdir(dir);
  return ok && seconds >= 0;
}

ViewshedFigures bench_viewshed(const std::string& dem_path, const Heightfield& hf, int range, int repeat, bool grass) {
  ViewshedFigures v;
  ViewshedParams p;
  p.observer_x = hf.x_of(hf.nx / 2);
  p.observer_y = hf.y_of(hf.ny / 2);
  p.observer_height_m = 2.0;
  p.target_height_m = 0.0;
  p.max_distance_m = range * hf.spacing_m;
  std::vector<double> t;
  Result<Viewshed> vs = Status(Errc::state, "not run");
  for (int n = 0; n < repeat; ++n) {
    const auto t0 = Clock::now();
    vs = compute_viewshed(hf, p);
    t.push_back(seconds_since(t0));
  }
  v.ours_s = median(t);
  if (!vs.ok()) return v;
  for (std::uint8_t c : vs->value) v.ours_visible += c == kViewshedVisible;
  if (!grass) {
    v.grass_note = "skipped";
    return v;
  }
  const std::string out = "/tmp/visvol-rviewshed-" + std::to_string(getpid()) + ".tif";
  std::vector<double> gt;
  for (int n = 0; n < repeat; ++n) {
    double s = -1;
    if (!run_grass(dem_path, p.observer_x, p.observer_y, p, out, s, v.grass_note)) return v;
    gt.push_back(s);
  }
  v.grass_s = median(gt);
  // r.viewshed marks visible cells with their vertical angle, the rest null.
  Result<RasterBand> theirs = read_band(out);
  std::remove(out.c_str());
  if (!theirs.ok() || theirs->nx != hf.nx || theirs->ny != hf.ny) {
    v.grass_note = "r.viewshed output unreadable";
    return v;
  }
  std::size_t agree = 0;
  for (std::size_t n = 0; n < vs->value.size(); ++n) {
    if (vs->value[n] == kViewshedOutside) continue;  // compare within the radius
    const bool ours = vs->value[n] == kViewshedVisible;
    const bool grass_visible = theirs->valid[n] != 0;
    v.grass_visible += grass_visible;
    ++v.compared;
    agree += ours == grass_visible;
  }
  v.agreement = v.compared ? double(agree) / double(v.compared) : 0.0;
  return v;
}

constexpr int kStreamLevels = 3;
// Issue 17's goals on this 2-core machine: F_p of the 512 case, the 2048 pack.
constexpr double kFieldGoalS = 2.0;
constexpr double kStreamGoalS = 60.0;

struct StreamFigures {
  bool ok = false;
  int n = 0;
  double wall_s = 0, rss_mib = 0, pack_mib = 0;
  // where the time went: F_p of each level of detail (finest first), its
  // hull and scatter phases, and the terrain force field over all levels
  double fp_s[kStreamLevels] = {}, hull_s[kStreamLevels] = {}, scatter_s[kStreamLevels] = {};
  double tff_s = 0;
  std::string error;
  double other_s() const {
    double s = wall_s - tff_s;
    for (double t : fp_s) s -= t;
    return s;
  }
};

// What the stream build's child sends its parent through a pipe: plain data.
struct StreamResult {
  int ok, n;
  double wall_s, pack_mib;
  double fp_s[kStreamLevels], hull_s[kStreamLevels], scatter_s[kStreamLevels], tff_s;
  char error[256];
};

// A pack build of a grid far larger than the field's working window: the
// Taunus DEM resampled to 22.5 m is 2048 x 2048 posts; 128 levels, range 64,
// three levels of detail. Run in a child so the peak RSS is the build's own.
StreamFigures bench_stream(const std::string& dem, int threads) {
  StreamFigures f;
  int fds[2];
  if (pipe(fds) != 0) return f;
  const std::string out = "/tmp/visvol-stream-" + std::to_string(getpid()) + ".vvp";
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    StreamResult r{};
    ImportOptions io;
    io.spacing_m = 22.5;
    io.nodata = NodataPolicy::fill;
    auto hf = import_dem(dem, io);
    if (!hf.ok()) {
      std::snprintf(r.error, sizeof r.error, "%s", hf.status().message().c_str());
    } else {
      r.n = hf->nx;
      storage::PackBuildParams p;
      p.field.nz = 128;
      p.field.range_posts = 64;
      p.field.threads = threads;
      p.lod_levels = kStreamLevels;
      storage::PackBuildReport report;
      const Status st = storage::build_pack(*hf, p, "{}", out, {}, &report);
      r.ok = st.ok();
      r.wall_s = report.wall_s;
      for (std::size_t l = 0; l < report.levels.size() && l < kStreamLevels; ++l) {
        r.fp_s[l] = report.levels[l].wall_s;
        r.hull_s[l] = report.levels[l].hull_s;
        r.scatter_s[l] = report.levels[l].scatter_s;
      }
      r.tff_s = report.tff_s;
      r.pack_mib = static_cast<double>(report.file_bytes) / (1024.0 * 1024.0);
      if (!st.ok()) std::snprintf(r.error, sizeof r.error, "%s", st.message().c_str());
    }
    std::remove(out.c_str());
    if (write(fds[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) _exit(3);
    _exit(0);
  }
  close(fds[1]);
  StreamResult r{};
  const ssize_t got = read(fds[0], &r, sizeof r);
  close(fds[0]);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  f.ok = got == static_cast<ssize_t>(sizeof r) && r.ok;
  f.n = r.n;
  f.wall_s = r.wall_s;
  f.pack_mib = r.pack_mib;
  for (int l = 0; l < kStreamLevels; ++l) {
    f.fp_s[l] = r.fp_s[l];
    f.hull_s[l] = r.hull_s[l];
    f.scatter_s[l] = r.scatter_s[l];
  }
  f.tff_s = r.tff_s;
  f.error = r.error;
  f.rss_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;
  std::remove(out.c_str());
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-fieldbench")) return 0;
  CLI::App app{"visvol-fieldbench: speed and memory of the visibility field build"};
  app.set_version_flag("--version",
                       visvol::version_line("visvol-fieldbench"));  // listed in --help; handled first in main
  std::string dem = std::string(VISVOL_TEST_DATA) + "/taunus_utm32n_90m_512.tif";
  int repeat = 3;
  int threads = 0;
  bool json = false;
  bool no_grass = false;
  bool no_exact = false;
  bool stream = false;
  std::vector<int> ranges{32, 64, 128};
  app.add_option("--dem", dem, "DEM in a metric CRS (512 x 512 for the target)")->capture_default_str();
  app.add_option("--repeat", repeat, "Runs per figure (the median is printed)")->capture_default_str();
  app.add_option("--ranges", ranges, "Cube ranges in posts")->capture_default_str();
  app.add_option("--threads", threads, "Worker threads, 0 for all cores")->capture_default_str();
  app.add_flag("--json", json, "Print one JSON object");
  app.add_flag("--no-grass", no_grass, "Skip the r.viewshed comparison");
  app.add_flag("--no-exact", no_exact, "Skip the exact-reference timing");
  app.add_flag("--stream", stream,
               "Also build a 2048 x 2048 x 128 pack (the DEM resampled to 22.5 m) and report its "
               "peak RSS (a minute or two)");
  visvol::decimal_numbers(app);
  CLI11_PARSE(app, argc, argv);
  if (repeat < 1 || repeat > 100) {
    std::fprintf(stderr, "visvol-fieldbench: --repeat %d is outside 1..100\n", repeat);
    return 2;
  }
  Result<Heightfield> hf = read_heightfield(dem, {NodataPolicy::fill});
  if (!hf.ok()) {
    std::fprintf(stderr, "visvol-fieldbench: %s\n", hf.status().message().c_str());
    return 2;
  }
  std::vector<RangeFigures> figures;
  for (int r : ranges) {
    if (!json) std::fprintf(stderr, "building range %d (%d runs)...\n", r, repeat);
    figures.push_back(bench_range(*hf, r, repeat, threads));
  }
  const ExactFigures exact = no_exact ? ExactFigures{} : bench_exact(*hf);
  const int vs_range = 64;
  const ViewshedFigures vs = bench_viewshed(dem, *hf, vs_range, repeat, !no_grass);

  StreamFigures streamed;
  if (stream) {
    if (!json) std::fprintf(stderr, "building a 2048 x 2048 x 128 pack...\n");
    streamed = bench_stream(dem, threads);
  }

  const RangeFigures* r64 = nullptr;
  for (const RangeFigures& f : figures)
    if (f.range == 64) r64 = &f;
  const bool hf512 = hf->nx == 512 && hf->ny == 512;
  if (json) {
    nlohmann::json j;
    j["dem"] = dem;
    j["nx"] = hf->nx;
    j["ny"] = hf->ny;
    j["nz"] = 128;
    j["repeat"] = repeat;
    j["goal_s"] = kFieldGoalS;  // 512 x 512 x 128 at range 64
    for (const RangeFigures& f : figures) {
      j["builds"].push_back({{"range_posts", f.range},
                             {"ok", f.ok},
                             {"wall_s", f.wall_s},
                             {"hull_s", f.hull_s},
                             {"scatter_s", f.scatter_s},
                             {"hull_cells", f.cells},
                             {"cells_per_s_per_core", f.mcells * 1e6},
                             {"peak_rss_mib", f.rss_mib},
                             {"threads", f.threads}});
    }
    if (!no_exact) {
      j["exact_reference"] = {{"grid", exact.n},
                              {"nz", exact.nz},
                              {"range_posts", exact.range},
                              {"fast_s", exact.fast_s},
                              {"exact_s", exact.exact_s},
                              {"ratio", exact.fast_s > 0 ? exact.exact_s / exact.fast_s : 0},
                              {"within_fraction", exact.within}};
    }
    if (stream) {
      nlohmann::json levels = nlohmann::json::array();
      for (int l = 0; l < kStreamLevels; ++l) {
        levels.push_back(
            {{"fp_s", streamed.fp_s[l]}, {"hull_s", streamed.hull_s[l]}, {"scatter_s", streamed.scatter_s[l]}});
      }
      j["stream_build"] = {{"ok", streamed.ok},
                           {"posts", streamed.n},
                           {"wall_s", streamed.wall_s},
                           {"goal_s", kStreamGoalS},
                           {"levels", levels},
                           {"tff_s", streamed.tff_s},
                           {"other_s", streamed.other_s()},
                           {"peak_rss_mib", streamed.rss_mib},
                           {"pack_mib", streamed.pack_mib},
                           {"error", streamed.error}};
    }
    j["viewshed"] = {{"radius_m", vs_range * hf->spacing_m},
                     {"visvol_s", vs.ours_s},
                     {"rviewshed_s", vs.grass_s},
                     {"agreement", vs.agreement},
                     {"visvol_visible", vs.ours_visible},
                     {"rviewshed_visible", vs.grass_visible},
                     {"note", vs.grass_note}};
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("visvol field benchmark: %s\n", dem.c_str());
  std::printf("%d x %d posts at %.0f m, 128 levels, cube range, 16 exact rings, %d threads, median of %d runs\n\n",
              hf->nx, hf->ny, hf->spacing_m, figures.empty() ? 0 : figures[0].threads, repeat);
  std::printf("range posts  wall s  hull s  scatter s  hull cells  Mcells/s/core  peak RSS MiB\n");
  for (const RangeFigures& f : figures) {
    std::printf("%11d  %6.2f  %6.2f  %9.2f  %10.3g  %13.1f  %12.1f%s\n", f.range, f.wall_s, f.hull_s, f.scatter_s,
                f.cells, f.mcells, f.rss_mib, f.ok ? "" : "  (FAILED)");
  }
  std::printf("(a hull cell is one observer-target column pair: one hull height, one voxel update)\n");
  if (r64 && hf512) {
    std::printf("\ngoal (issue 17): 512 x 512 x 128 at range 64 in at most %.0f s: %.2f s, %s\n", kFieldGoalS,
                r64->wall_s, r64->wall_s <= kFieldGoalS ? "met" : "NOT met");
  }
  if (!no_exact) {
    std::printf(
        "\nexact R3 reference, %d x %d x %d at range %d, one thread: fast %.3f s, exact %.1f s, "
        "ratio %.0fx; %.2f%% of voxels within the accuracy bracket\n",
        exact.n, exact.n, exact.nz, exact.range, exact.fast_s, exact.exact_s,
        exact.fast_s > 0 ? exact.exact_s / exact.fast_s : 0.0, 100.0 * exact.within);
  }
  if (stream) {
    if (streamed.ok) {
      std::printf(
          "\nstreamed pack build %d x %d x 128, range 64, %d levels of detail: %.1f s (goal, issue 17: at most "
          "%.0f s, %s), peak RSS %.0f MiB (target under 1536 MiB: %s), pack %.0f MiB\n",
          streamed.n, streamed.n, kStreamLevels, streamed.wall_s, kStreamGoalS,
          streamed.wall_s <= kStreamGoalS ? "met" : "NOT met", streamed.rss_mib,
          streamed.rss_mib < 1536.0 ? "met" : "NOT met", streamed.pack_mib);
      std::printf("  F_p by level (finest first):");
      for (int l = 0; l < kStreamLevels; ++l) {
        std::printf(" %.1f s (hull %.1f, scatter %.1f)%s", streamed.fp_s[l], streamed.hull_s[l], streamed.scatter_s[l],
                    l + 1 < kStreamLevels ? "," : "");
      }
      std::printf(
          "\n  terrain force field %.1f s, the rest (levels of detail, height and area tiles, the pack's end and "
          "sync; the import is not counted) %.1f s\n",
          streamed.tff_s, streamed.other_s());
    } else {
      std::printf("\nstreamed pack build failed: %s\n", streamed.error.c_str());
    }
  }
  std::printf("\nviewshed, observer at the grid centre 2 m up, target 0 m, radius %.0f m:\n", vs_range * hf->spacing_m);
  std::printf("  visvol      %.4f s, %zu cells visible\n", vs.ours_s, vs.ours_visible);
  if (vs.grass_s >= 0) {
    std::printf("  r.viewshed  %.4f s, %zu cells visible (its own timing inside GRASS)\n", vs.grass_s,
                vs.grass_visible);
    std::printf("  agreement   %.2f%% of %zu cells in range\n", 100.0 * vs.agreement, vs.compared);
  } else {
    std::printf("  r.viewshed  not run: %s\n", vs.grass_note.c_str());
  }
  return 0;
}
