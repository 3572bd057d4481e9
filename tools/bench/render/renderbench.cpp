// visvol-renderbench: milliseconds per thumbnail, drawing and PNG apart, for
// each view at 256 x 256 and 1024 x 768, and memory over many frames.
//
//   visvol-renderbench [--pack PACK] [--frames N] [Google Benchmark flags]
//
// Without --pack it builds the bundled SF North DEM (370 x 466 posts, 30 m,
// 128 levels, range 64, as the demo's level 0) into a temporary pack first.
// The path is a 129-vertex arc across the terrain 80 m above the ground (a
// 128-segment rope), with F_p sampled on level 0, and one hidden-from and one
// visible-to point. One renderer made at 1024 x 768 (the console's: one
// context, bound once) draws every size.
//
// Prints, in order: the memory check (--frames frames, 1000 by default, of
// every view in turn at both sizes with their PNG: resident memory at five
// points, heap in use, operator new calls, and whether it stayed flat), Google Benchmark's table (medians of 5
// repetitions), then a summary of the medians against the targets of issue 8:
// at most 30 ms a thumbnail (drawing plus PNG at zlib level 1) at 256 x 256
// for the surface views (top, oblique; slice too), at most 250 ms for the
// volume view.
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "base/version.hpp"
#include "drivers/render/png_encoder.hpp"
#include "drivers/render/renderer.hpp"
#include "fields/gdal/dem_import.hpp"
#include "fields/sampler.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "tests/support/alloc_counter.hpp"

namespace {

using namespace visvol;
using render::Frame;
using render::View;

struct Bench {
  std::shared_ptr<const storage::Pack> pack;
  std::unique_ptr<render::Renderer> renderer;
  std::vector<render::PathPoint> path;
  std::vector<render::Marker> markers;
  std::vector<std::uint8_t> png;
  std::unique_ptr<render::PngEncoder> level6;
};
Bench* g_bench = nullptr;

Frame frame_for(View view, int width, int height) {
  Frame f;
  f.view = view;
  f.width_px = width;
  f.height_px = height;
  f.path = g_bench->path.data();
  f.path_size = g_bench->path.size();
  f.markers = g_bench->markers.data();
  f.marker_count = g_bench->markers.size();
  return f;
}

void render_or_die(const Frame& f) {
  const Status s = g_bench->renderer->render(f);
  if (!s.ok()) {
    std::fprintf(stderr, "visvol-renderbench: %s\n", s.message().c_str());
    std::exit(1);
  }
}

void BM_Render(benchmark::State& state, View view, int width, int height) {
  const Frame f = frame_for(view, width, height);
  render_or_die(f);
  for (auto _ : state) render_or_die(f);
}

void BM_Png(benchmark::State& state, View view, int width, int height, int level) {
  render_or_die(frame_for(view, width, height));
  const render::Image im = g_bench->renderer->image();
  std::size_t bytes = 0;
  for (auto _ : state) {
    Result<std::size_t> r = level == g_bench->renderer->config().png_compression_level
                                ? g_bench->renderer->encode_png(g_bench->png.data(), g_bench->png.size())
                                : g_bench->level6->encode(im.rgba, im.width_px, im.height_px, im.stride_bytes,
                                                          g_bench->png.data(), g_bench->png.size());
    if (!r.ok()) {
      state.SkipWithError(r.status().message().c_str());
      return;
    }
    bytes = *r;
  }
  state.counters["png_KiB"] = static_cast<double>(bytes) / 1024.0;
}

double rss_mib() {
  long pages = 0, resident = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  std::fclose(f);
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// malloc's bytes in use, and its footprint (in use plus free chunks it keeps).
double heap_mib() {
  const struct mallinfo2 mi = mallinfo2();
  return static_cast<double>(mi.uordblks + mi.hblkhd) / (1024.0 * 1024.0);
}
double heap_footprint_mib() {
  const struct mallinfo2 mi = mallinfo2();
  return static_cast<double>(mi.arena + mi.hblkhd) / (1024.0 * 1024.0);
}

// What "flat" allows. malloc's bytes in use must not grow (a leak through
// malloc, Mesa's included, shows there). Resident memory may grow while
// glibc's arenas settle: llvmpipe's threads malloc and free per frame, and
// the arenas' footprint grows by about 1 to 2 MiB over the first 2000 frames
// with the bytes in use flat, then stops (measured over 4000 frames). A leak
// of one frame buffer or PNG a frame would add hundreds of MiB over 1000.
constexpr double kFlatHeapInUseMib = 0.0625;
constexpr double kFlatRssMib = 4.0;

// Frames of every view in turn, every fourth at 1024 x 768 and the rest at
// 256 x 256 (sizes change as the console's do), each with its PNG: resident
// memory after a warm-up and at four points after, malloc's bytes in use and
// footprint, and operator new calls on this (the renderer's) thread.
bool memory_report(int frames) {
  const View views[] = {View::top, View::oblique, View::volume, View::slice};
  const auto one = [&](int n) {
    const bool large = n % 4 == 3;
    render_or_die(frame_for(views[n % 4 == 3 ? (n / 4) % 4 : n % 4], large ? 1024 : 256, large ? 768 : 256));
    if (!g_bench->renderer->encode_png(g_bench->png.data(), g_bench->png.size()).ok()) std::exit(1);
  };
  for (int n = 0; n < 40; ++n) one(n);
  double rss[5] = {rss_mib(), 0, 0, 0, 0};
  const double heap0 = heap_mib(), footprint0 = heap_footprint_mib();
  const std::uint64_t news0 = testing::thread_allocation_count();
  const auto t0 = std::chrono::steady_clock::now();
  for (int n = 0, mark = 1; n < frames; ++n) {
    one(n);
    while (mark <= 4 && (n + 1) * 4 >= mark * frames) rss[mark++] = rss_mib();
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::uint64_t news = testing::thread_allocation_count() - news0;
  const double heap1 = heap_mib(), footprint1 = heap_footprint_mib();
  const double growth = *std::max_element(rss + 1, rss + 5) - rss[0];
#ifdef VISVOL_SANITIZED
  // ASan's quarantine and shadow memory move RSS by megabytes: only the
  // allocation count means something here (LeakSanitizer covers leaks)
  const bool flat = news == 0;
  const char* criterion = "sanitized build: no operator new; RSS not judged";
#else
  const bool flat = news == 0 && heap1 - heap0 < kFlatHeapInUseMib && growth < kFlatRssMib;
  const char* criterion = "no operator new, heap in use grown under 64 KiB, RSS under 4 MiB";
#endif
  std::printf(
      "memory over %d frames (every view; 3 of 4 at 256 x 256, 1 of 4 at 1024 x 768; each with its PNG):\n"
      "  RSS after the warm-up and each quarter: %.1f, %.1f, %.1f, %.1f, %.1f MiB (largest growth %+.2f MiB)\n"
      "  heap in use %.2f -> %.2f MiB (%+.3f), malloc's footprint %.2f -> %.2f MiB; operator new calls %llu;\n"
      "  %.1f ms a frame on average\n"
      "  flat: %s (%s)\n\n",
      frames, rss[0], rss[1], rss[2], rss[3], rss[4], growth, heap0, heap1, heap1 - heap0, footprint0, footprint1,
      static_cast<unsigned long long>(news), ms / frames, flat ? "yes" : "NO", criterion);
  return flat;
}

// Google Benchmark's console table, keeping each benchmark's median (ms).
class MedianReporter : public benchmark::ConsoleReporter {
 public:
  // colours only on a terminal (Google Benchmark's own default)
  MedianReporter() : ConsoleReporter(isatty(STDOUT_FILENO) ? OO_ColorTabular : OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median" && !r.error_occurred) {
        median_ms[r.run_name.function_name] = r.GetAdjustedRealTime();
        median_cpu_ms[r.run_name.function_name] = r.GetAdjustedCPUTime();
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> median_ms;      // wall clock
  std::map<std::string, double> median_cpu_ms;  // the whole process's CPU (llvmpipe's threads too)
};

// Medians per view and size: drawing, PNG (level 1, the renderer's default),
// their sum, and the target for it (wall clock, which a loaded
// machine inflates); and the drawing's CPU time over all threads, which it
// does not much (on an idle 2-core machine the wall time is about half of it
// plus the serial part).
void print_summary(const MedianReporter& r) {
  const auto at = [](const std::map<std::string, double>& m, const std::string& name) {
    const auto it = m.find(name);
    return it == m.end() ? -1.0 : it->second;
  };
  std::printf(
      "\nmedians, ms a thumbnail (render: draw + read back; PNG at zlib level 1, level 6 for comparison;\n"
      "render CPU: all threads; target: render + png1 wall clock)\n");
  std::printf("%-8s %-9s %8s %8s %8s %8s %10s  %s\n", "view", "size", "render", "png1", "total", "png6", "render CPU",
              "target");
  for (const char* size : {"256x256", "1024x768"}) {
    for (View v : {View::top, View::oblique, View::volume, View::slice}) {
      const std::string view = render::to_string(v), suffix = view + "/" + size;
      const double draw = at(r.median_ms, "render/" + suffix), png = at(r.median_ms, "png_level1/" + suffix);
      const double png6 = at(r.median_ms, "png_level6/" + suffix), cpu = at(r.median_cpu_ms, "render/" + suffix);
      if (draw < 0 || png < 0) continue;  // filtered out
      const double target = v == View::volume ? 250.0 : (std::string(size) == "256x256" ? 30.0 : -1.0);
      char verdict[48] = "-";
      if (target > 0) {
        std::snprintf(verdict, sizeof verdict, "<= %.0f: %s", target, draw + png <= target ? "met" : "NOT met");
      }
      char six[16] = "-";
      if (png6 >= 0) std::snprintf(six, sizeof six, "%.2f", png6);
      std::printf("%-8s %-9s %8.2f %8.2f %8.2f %8s %10.2f  %s\n", view.c_str(), size, draw, png, draw + png, six, cpu,
                  verdict);
    }
  }
  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) == 3) {
    std::printf("load average now %.2f (%ld cores)\n", load[0], sysconf(_SC_NPROCESSORS_ONLN));
  }
}

Result<std::string> build_default_pack() {
  fields::ImportOptions io;
  io.nodata = fields::NodataPolicy::fill;
  Result<fields::Heightfield> hf = fields::import_dem(std::string(VISVOL_TEST_DATA) + "/sf_north_utm10_30m.tif", io);
  if (!hf.ok()) return hf.status();
  storage::PackBuildParams p;
  p.field.nz = 128;
  p.field.range_posts = 64;
  p.lod_levels = 1;
  p.tff.band_levels = 4;
  const std::string out = "/tmp/visvol-renderbench-" + std::to_string(getpid()) + ".vvp";
  VISVOL_RETURN_IF_ERROR(storage::build_pack(*hf, p, "{}", out));
  return out;
}

// A 128-segment arc from the south-west to the north-east, 80 m above the ground.
std::vector<render::PathPoint> arc_path(const storage::PackLevel& level) {
  const fields::FieldSampler<storage::PackLevel> s(level);
  const fields::VolumeGeometry& g = level.geometry();
  const double w = (g.nx - 1) * g.spacing_m, h = (g.ny - 1) * g.spacing_m;
  std::vector<render::PathPoint> out;
  for (int i = 0; i <= 128; ++i) {
    const double t = i / 128.0;
    const double x = g.origin_x + w * (0.15 + 0.7 * t);
    const double y = g.origin_y - h * (0.85 - 0.7 * t) + 0.2 * h * std::sin(3.14159265 * t);
    const double z = s.height(x, y) + 80.0;
    out.push_back({x, y, z, std::clamp(s.visibility(x, y, z), 0.0, 1.0)});
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-renderbench")) return 0;
  std::string pack_path;
  int frames = 1000;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf(
          "visvol-renderbench [--pack PACK] [--frames N] [Google Benchmark options]\n"
          "  Milliseconds per thumbnail (render and PNG separately) for every view at 256 x 256 and\n"
          "  1024 x 768, after a memory check over N frames (1000). Without --pack it builds the\n"
          "  SF North pack from the bundled DEM into /tmp first.\n");
      return 0;
    }
    if (std::strcmp(argv[i], "--pack") == 0 && i + 1 < argc) {
      pack_path = argv[++i];
    } else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = std::atoi(argv[++i]);
      if (frames < 1) {
        std::fprintf(stderr, "visvol-renderbench: --frames needs a positive count\n");
        return 2;
      }
    } else {
      rest.push_back(argv[i]);
    }
  }
  bool temporary = false;
  if (pack_path.empty()) {
    std::printf("building the SF North pack (370 x 466 posts, 128 levels, range 64) ...\n");
    Result<std::string> built = build_default_pack();
    if (!built.ok()) {
      std::fprintf(stderr, "visvol-renderbench: %s\n", built.status().message().c_str());
      return 1;
    }
    pack_path = *built;
    temporary = true;
  }
  Bench bench;
  g_bench = &bench;
  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(pack_path);
  if (temporary) std::remove(pack_path.c_str());  // mapped: the file lives on until exit
  if (!pack.ok()) {
    std::fprintf(stderr, "visvol-renderbench: %s\n", pack.status().message().c_str());
    return 2;
  }
  bench.pack = *pack;
  Result<storage::PackLevel> level = storage::PackLevel::open(bench.pack, 0);
  if (!level.ok()) {
    std::fprintf(stderr, "visvol-renderbench: %s\n", level.status().message().c_str());
    return 2;
  }
  bench.path = arc_path(*level);
  const fields::VolumeGeometry& g = level->geometry();
  bench.markers = {{render::MarkerKind::hidden_from, g.origin_x + 0.3 * (g.nx - 1) * g.spacing_m,
                    g.origin_y - 0.3 * (g.ny - 1) * g.spacing_m, g.top_m() * 0.5},
                   {render::MarkerKind::visible_to, g.origin_x + 0.7 * (g.nx - 1) * g.spacing_m,
                    g.origin_y - 0.6 * (g.ny - 1) * g.spacing_m, g.top_m() * 0.5}};

  render::RendererConfig config;  // 1024 x 768 at most, zlib level 1
  const auto t0 = std::chrono::steady_clock::now();
  Result<std::unique_ptr<render::Renderer>> r = render::Renderer::create(bench.pack, config);
  if (!r.ok()) {
    std::fprintf(stderr, "visvol-renderbench: %s\n", r.status().message().c_str());
    return 1;
  }
  const double create_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  bench.renderer = std::move(*r);
  bench.png.resize(render::PngEncoder::worst_case_bytes(config.max_width_px, config.max_height_px));
  bench.level6 = std::move(render::PngEncoder::create(config.max_width_px, config.max_height_px, 6).value());
  const render::SceneInfo& info = bench.renderer->scene_info();
  std::string steps;
  for (int s : info.mesh_steps) steps += (steps.empty() ? "" : ", ") + std::to_string(s);
  std::printf(
      "pack %s: %d x %d posts; meshes every %s posts; F_p texture %d x %d x %d (%d x %d posts a texel), "
      "F_p scale top %.3g; exaggeration %.1f\n",
      pack_path.c_str(), info.terrain_nx, info.terrain_ny, steps.c_str(), info.volume_nx, info.volume_ny,
      info.volume_nz, info.volume_stride, info.volume_stride, info.fp_max, info.vertical_exaggeration);
  std::printf("%s, %s; create (read the pack, build, compile, warm up) %.0f ms\n", info.gl_renderer.c_str(),
              info.gl_version.c_str(), create_ms);
  const bool flat = memory_report(frames);

  struct Size {
    int w, h;
  };
  for (Size s : {Size{256, 256}, Size{1024, 768}}) {
    for (View v : {View::top, View::oblique, View::volume, View::slice}) {
      const std::string size = std::to_string(s.w) + "x" + std::to_string(s.h);
      benchmark::RegisterBenchmark(("render/" + std::string(render::to_string(v)) + "/" + size).c_str(), BM_Render, v,
                                   s.w, s.h)
          ->Unit(benchmark::kMillisecond)
          ->MeasureProcessCPUTime()  // llvmpipe draws on worker threads: count them
          ->UseRealTime()
          ->MinTime(0.3)
          ->Repetitions(5)
          ->ReportAggregatesOnly(true);
      for (int zlib : {1, 6}) {
        if (zlib == 6 && v != View::oblique && v != View::volume) continue;
        benchmark::RegisterBenchmark(
            ("png_level" + std::to_string(zlib) + "/" + render::to_string(v) + "/" + size).c_str(), BM_Png, v, s.w, s.h,
            zlib)
            ->Unit(benchmark::kMillisecond)
            ->MeasureProcessCPUTime()
            ->UseRealTime()
            ->MinTime(0.3)
            ->Repetitions(5)
            ->ReportAggregatesOnly(true);
      }
    }
  }
  int bench_argc = static_cast<int>(rest.size());
  benchmark::Initialize(&bench_argc, rest.data());
  MedianReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  print_summary(reporter);
  return flat ? 0 : 1;  // 1: memory grew (the figures above say how)
}
