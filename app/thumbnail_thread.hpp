// The console's renderer thread: thumbnails of the plan, drawn from the
// latest path the executive hands off, when the rope comes to rest (and at
// most `max_hz`), published to DDS and kept for the console's outputs.
//
// Not real-time: a frame takes tens of milliseconds. The renderer and its
// buffers (framebuffers at the thumbnail size, the PNG arena, the terrain
// mesh and F_p texture of the pack's finest level) are made at create() on
// this thread's own context; render and encode allocate nothing after that.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "drivers/render/renderer.hpp"
#include "msg/samples.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::app {

struct ThumbnailConfig {
  render::View view = render::View::oblique;
  int width_px = 256, height_px = 256;
  double max_hz = 1.0;            // thumbnails a second at most
  int png_compression_level = 6;  // zlib 0..9
};

struct ThumbnailStats {
  std::uint64_t rendered = 0;
  std::uint64_t failed = 0;
  double last_render_ms = 0;  // render and encode of the last thumbnail
};

class ThumbnailThread {
 public:
  // Makes the renderer on a new thread and waits for it; `sink` (may be
  // null) receives every thumbnail (the DDS publisher's slot).
  static Result<std::unique_ptr<ThumbnailThread>> start(std::shared_ptr<const storage::Pack> pack,
                                                        const ThumbnailConfig& config,
                                                        LatestValue<msg::ThumbnailSample>* sink);
  ~ThumbnailThread();
  ThumbnailThread(const ThumbnailThread&) = delete;
  ThumbnailThread& operator=(const ThumbnailThread&) = delete;

  // The executive's path hand-off to this thread (ExecutiveOutputs::path_render).
  LatestValue<msg::PathSample>& paths() { return paths_; }

  // Stops the thread after one last thumbnail of the newest path (converged
  // or not), so the outputs show where the rope ended. Idempotent.
  void stop();
  ThumbnailStats stats() const;
  // The last thumbnail as a PNG file, written whole or not at all; an error
  // when there is none.
  Status write_last(const std::string& path) const;
  const render::SceneInfo& scene() const { return scene_; }

 private:
  ThumbnailThread() = default;
  void run(std::shared_ptr<const storage::Pack> pack, Status* created, std::atomic<bool>* ready);
  bool due(const msg::PathSample& path, std::int64_t now_ns) const;
  void draw(const msg::PathSample& path, std::int64_t now_ns);

  ThumbnailConfig config_;
  LatestValue<msg::ThumbnailSample>* sink_ = nullptr;
  LatestValue<msg::PathSample> paths_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<render::PathPoint[]> scratch_;
  std::unique_ptr<msg::ThumbnailSample> last_;  // owned by the thread until it stops
  std::unique_ptr<msg::PathSample> newest_;     // newest path seen
  bool have_newest_ = false, newest_drawn_ = false, have_last_ = false;
  std::int64_t last_draw_ns_ = 0;
  std::atomic<std::uint64_t> rendered_{0}, failed_{0};
  std::atomic<double> last_render_ms_{0};
  render::SceneInfo scene_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace visvol::app
