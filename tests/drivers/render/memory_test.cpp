// Memory flat over 300 frames on a renderer thread, as the console runs it
// (render_thumbnail: a PathSample in, a ThumbnailSample out): every view in
// turn, two sizes, the path moving and changing length each frame. The frames
// allocate nothing through operator new on that thread, and resident memory
// and the C heap stay flat.
#include <gtest/gtest.h>
#include <malloc.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <thread>

#include "drivers/render/renderer.hpp"
#include "drivers/render/thumbnail.hpp"
#include "msg/samples.hpp"
#include "render_test_util.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::render {
namespace {

constexpr int kWarmupFrames = 40;
constexpr int kFrames = 300;

std::size_t rss_bytes() {
  long pages = 0, resident = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  std::fclose(f);
  return static_cast<std::size_t>(resident) * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

std::size_t heap_bytes() {
  const struct mallinfo2 mi = mallinfo2();
  return mi.uordblks + mi.hblkhd;
}

struct Measures {
  Status status;
  std::uint64_t allocations = 0;
  std::size_t rss_before = 0, rss_after = 0, heap_before = 0, heap_after = 0;
  std::size_t png_bytes = 0;
  int frames = 0;
  bool counter_works = false;
};

TEST(RendererMemory, FlatOverThreeHundredFramesOnARendererThread) {
  const std::string pack_path = testing::build_prism_pack("render_memory");
  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(pack_path);
  ASSERT_TRUE(pack.ok()) << pack.status().message();
  const fields::VolumeGeometry g = (*pack)->geometry(0);

  Measures m;
  // the console's renderer thread: it makes the renderer and keeps it
  std::thread renderer_thread([&] {
    RendererConfig config;
    config.max_width_px = 256;
    config.max_height_px = 256;
    Result<std::unique_ptr<Renderer>> r = Renderer::create(*pack, config);
    if (!r.ok()) {
      m.status = r.status();
      return;
    }
    auto thumbnail = std::make_unique<msg::ThumbnailSample>();
    auto sample = std::make_unique<msg::PathSample>();
    auto scratch = std::make_unique<PathPoint[]>(msg::kMaxPathVertices);
    const Marker markers[2] = {{MarkerKind::hidden_from, g.origin_x + 100, g.origin_y - 500, 20},
                               {MarkerKind::visible_to, g.origin_x + 500, g.origin_y - 540, 20}};
    const View views[4] = {View::top, View::oblique, View::volume, View::slice};
    const double cx = g.origin_x + (g.nx - 1) * g.spacing_m / 2, cy = g.origin_y - (g.ny - 1) * g.spacing_m / 2;
    const auto frame = [&](int n) {
      // a path that moves and changes length every frame, as a settling rope does
      const std::size_t count = 64 + static_cast<std::size_t>(n % 5) * 100;
      sample->stamp_ns = 1000 + n;
      sample->vertex_count = static_cast<std::uint32_t>(count);
      for (std::size_t i = 0; i < count; ++i) {
        const double t = static_cast<double>(i) / static_cast<double>(count - 1);
        const double a = 5.0 * t + 0.01 * n;
        sample->vertices[i] = {
            {cx + 200 * std::cos(a), cy + 180 * std::sin(a), 80 + 20 * std::sin(0.1 * n + t)}, t * 0.1, 50.0};
      }
      Frame f;
      f.view = views[n % 4];
      f.width_px = n % 3 == 0 ? 256 : 200;  // sizes vary too: one context, bound once
      f.height_px = n % 3 == 0 ? 256 : 150;
      f.markers = markers;
      f.marker_count = 2;
      if (n % 2) f.height_above_ground_m = 15.0;
      Status s = render_thumbnail(**r, *sample, f, scratch.get(), *thumbnail);
      if (!s.ok()) return s;
      if (thumbnail->stamp_ns != 1000 + n) return Status(Errc::state, "thumbnail not stamped with its path");
      m.png_bytes = thumbnail->png_size_bytes;
      return Status::ok_status();
    };
    for (int n = 0; n < kWarmupFrames; ++n) {
      if (m.status = frame(n); !m.status.ok()) return;
    }
    m.rss_before = rss_bytes();
    m.heap_before = heap_bytes();
    const std::uint64_t before = visvol::testing::thread_allocation_count();
    for (int n = kWarmupFrames; n < kWarmupFrames + kFrames; ++n) {
      if (m.status = frame(n); !m.status.ok()) return;
      ++m.frames;
    }
    m.allocations = visvol::testing::thread_allocation_count() - before;
    // the counter sees this thread's allocations (so the zero above means something)
    const std::uint64_t probe_before = visvol::testing::thread_allocation_count();
    auto probe = std::make_unique<int>(1);
    m.counter_works = visvol::testing::thread_allocation_count() == probe_before + 1 && *probe == 1;
    m.rss_after = rss_bytes();
    m.heap_after = heap_bytes();
  });
  renderer_thread.join();
  std::remove(pack_path.c_str());
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  ASSERT_EQ(m.frames, kFrames);
  EXPECT_GT(m.png_bytes, 1000u);
  EXPECT_TRUE(m.counter_works);
  EXPECT_EQ(m.allocations, 0u) << "operator new on the renderer thread during frames";
  const double rss_growth_kib = (static_cast<double>(m.rss_after) - static_cast<double>(m.rss_before)) / 1024.0;
  const double heap_growth_kib = (static_cast<double>(m.heap_after) - static_cast<double>(m.heap_before)) / 1024.0;
  std::printf("over %d frames: RSS %.1f -> %.1f MiB (%+.0f KiB), heap in use %+.0f KiB\n", kFrames,
              static_cast<double>(m.rss_before) / 1048576.0, static_cast<double>(m.rss_after) / 1048576.0,
              rss_growth_kib, heap_growth_kib);
#ifdef VISVOL_SANITIZED
  // ASan keeps freed blocks in quarantine and replaces malloc: RSS and
  // mallinfo say nothing about leaks there (LeakSanitizer does instead).
  std::printf("sanitized build: RSS and heap figures not checked\n");
#else
  EXPECT_LT(rss_growth_kib, 512.0) << "resident memory grew over " << kFrames << " frames";
  EXPECT_LT(std::fabs(heap_growth_kib), 64.0) << "heap in use changed over " << kFrames << " frames";
#endif
}

}  // namespace
}  // namespace visvol::render
