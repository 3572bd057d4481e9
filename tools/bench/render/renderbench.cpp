// visvol-renderbench: milliseconds per thumbnail, drawing and PNG apart, for
// each view at 256 x 256 and 1024 x 768, and memory over many frames.
//
//   visvol-renderbench [--pack PACK] [--frames N] [Google Benchmark flags]
//
// Without --pack it builds the bundled SF North DEM (370 x 466 posts, 30 m,
// 128 levels, range 64, as the demo's level 0) into a temporary pack first.
// The path is a 129-vertex arc across the terrain 80 m above the ground (a
// 128-segment rope), with F_p sampled on level 0, and one hidden-from and one
// visible-to point. Figures are medians of 5 repetitions.
//
// Targets (issue 8): at most 30 ms for 256 x 256 (surface views), at most
// 250 ms for the volume view.
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "drivers/render/png_encoder.hpp"
#include "drivers/render/renderer.hpp"
#include "fields/gdal/dem_import.hpp"
#include "fields/sampler.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"

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

double heap_mib() {
  const struct mallinfo2 mi = mallinfo2();
  return static_cast<double>(mi.uordblks + mi.hblkhd) / (1024.0 * 1024.0);
}

// Frames of every view in turn at 256 x 256 with their PNG: RSS and heap in
// use after a warm-up and after `frames` more.
void memory_report(int frames) {
  const View views[] = {View::top, View::oblique, View::volume, View::slice};
  const auto one = [&](int n) {
    render_or_die(frame_for(views[n % 4], 256, 256));
    if (!g_bench->renderer->encode_png(g_bench->png.data(), g_bench->png.size()).ok()) std::exit(1);
  };
  for (int n = 0; n < 40; ++n) one(n);
  const double rss0 = rss_mib(), heap0 = heap_mib();
  const auto t0 = std::chrono::steady_clock::now();
  for (int n = 0; n < frames; ++n) one(n);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double rss1 = rss_mib(), heap1 = heap_mib();
  std::printf("memory over %d frames (views in turn, 256 x 256, with PNG): RSS %.1f -> %.1f MiB (%+.2f), "
              "heap in use %.2f -> %.2f MiB (%+.3f); %.1f ms a frame on average\n\n",
              frames, rss0, rss1, rss1 - rss0, heap0, heap1, heap1 - heap0, ms / frames);
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
  std::string pack_path;
  int frames = 1000;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
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
  std::printf("pack %s: %d x %d posts; meshes every %s posts; F_p texture %d x %d x %d (%d x %d posts a texel), "
              "F_p scale top %.3g; exaggeration %.1f\n",
              pack_path.c_str(), info.terrain_nx, info.terrain_ny, steps.c_str(), info.volume_nx, info.volume_ny,
              info.volume_nz, info.volume_stride, info.volume_stride, info.fp_max, info.vertical_exaggeration);
  std::printf("%s, %s; create (read the pack, build, compile, warm up) %.0f ms\n", info.gl_renderer.c_str(),
              info.gl_version.c_str(), create_ms);
  memory_report(frames);

  struct Size {
    int w, h;
  };
  for (Size s : {Size{256, 256}, Size{1024, 768}}) {
    for (View v : {View::top, View::oblique, View::volume, View::slice}) {
      const std::string size = std::to_string(s.w) + "x" + std::to_string(s.h);
      benchmark::RegisterBenchmark(("render/" + std::string(render::to_string(v)) + "/" + size).c_str(), BM_Render, v,
                                   s.w, s.h)
          ->Unit(benchmark::kMillisecond)
          ->MinTime(0.3)
          ->Repetitions(5)
          ->ReportAggregatesOnly(true);
      for (int zlib : {1, 6}) {
        if (zlib == 6 && v != View::oblique && v != View::volume) continue;
        benchmark::RegisterBenchmark(
            ("png_level" + std::to_string(zlib) + "/" + render::to_string(v) + "/" + size).c_str(), BM_Png, v, s.w,
            s.h, zlib)
            ->Unit(benchmark::kMillisecond)
            ->MinTime(0.3)
            ->Repetitions(5)
            ->ReportAggregatesOnly(true);
      }
    }
  }
  int bench_argc = static_cast<int>(rest.size());
  benchmark::Initialize(&bench_argc, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
