#include "app/thumbnail_thread.hpp"

#include <chrono>
#include <cmath>

#include "drivers/render/thumbnail.hpp"
#include "io/atomic_file.hpp"

namespace visvol::app {

namespace {

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

constexpr auto kPoll = std::chrono::milliseconds(20);

}  // namespace

Result<std::unique_ptr<ThumbnailThread>> ThumbnailThread::start(std::shared_ptr<const storage::Pack> pack,
                                                                const ThumbnailConfig& config,
                                                                LatestValue<msg::ThumbnailSample>* sink) {
  if (!(config.max_hz > 0 && config.max_hz <= 50)) {
    return invalid_argument("thumbnail rate: " + std::to_string(config.max_hz) + " Hz is not in (0, 50]");
  }
  std::unique_ptr<ThumbnailThread> t(new ThumbnailThread());
  t->config_ = config;
  t->sink_ = sink;
  t->scratch_ = std::make_unique<render::PathPoint[]>(msg::kMaxPathVertices);
  t->last_ = std::make_unique<msg::ThumbnailSample>();
  t->newest_ = std::make_unique<msg::PathSample>();
  // The renderer is made on its own thread: its GL context stays bound there.
  Status created;
  std::atomic<bool> ready{false};
  t->thread_ = std::thread(&ThumbnailThread::run, t.get(), std::move(pack), &created, &ready);
  while (!ready.load(std::memory_order_acquire)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (!created.ok()) {
    t->thread_.join();
    return created;
  }
  return t;
}

ThumbnailThread::~ThumbnailThread() { stop(); }

void ThumbnailThread::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void ThumbnailThread::run(std::shared_ptr<const storage::Pack> pack, Status* created, std::atomic<bool>* ready) {
  render::RendererConfig rc;
  rc.max_width_px = config_.width_px;
  rc.max_height_px = config_.height_px;
  rc.png_compression_level = config_.png_compression_level;
  auto r = render::Renderer::create(std::move(pack), rc);
  if (r.ok()) {
    renderer_ = std::move(*r);
    scene_ = renderer_->scene_info();
  } else {
    *created = r.status();
  }
  const bool ok = r.ok();
  ready->store(true, std::memory_order_release);  // `created` and `ready` die with start()'s frame
  if (!ok) return;
  bool drawn_since_rest = false;
  while (!stop_.load(std::memory_order_acquire)) {
    if (const msg::PathSample* p = paths_.take()) {
      *newest_ = *p;
      have_newest_ = true;
      newest_drawn_ = false;
      if (!p->converged) drawn_since_rest = false;
    }
    const std::int64_t now = steady_ns();
    if (have_newest_ && newest_->converged && !drawn_since_rest && due(*newest_, now)) {
      draw(*newest_, now);
      drawn_since_rest = true;
    }
    std::this_thread::sleep_for(kPoll);
  }
  // the last picture shows where the rope ended
  if (const msg::PathSample* p = paths_.take()) {
    *newest_ = *p;
    have_newest_ = true;
    newest_drawn_ = false;
  }
  if (have_newest_ && !newest_drawn_) draw(*newest_, steady_ns());
}

bool ThumbnailThread::due(const msg::PathSample&, std::int64_t now_ns) const {
  return rendered_.load() == 0 || static_cast<double>(now_ns - last_draw_ns_) >= 1e9 / config_.max_hz;
}

void ThumbnailThread::draw(const msg::PathSample& path, std::int64_t now_ns) {
  if (path.vertex_count < 2) return;
  render::Frame frame;
  frame.view = config_.view;
  frame.width_px = config_.width_px;
  frame.height_px = config_.height_px;
  const std::int64_t t0 = steady_ns();
  const Status s = render::render_thumbnail(*renderer_, path, frame, scratch_.get(), *last_);
  last_draw_ns_ = now_ns;
  newest_drawn_ = true;
  if (!s.ok()) {
    failed_.fetch_add(1);
    return;
  }
  last_render_ms_.store(static_cast<double>(steady_ns() - t0) * 1e-6);
  have_last_ = true;
  if (sink_) sink_->write(*last_);
  rendered_.fetch_add(1);
}

ThumbnailStats ThumbnailThread::stats() const { return {rendered_.load(), failed_.load(), last_render_ms_.load()}; }

Status ThumbnailThread::write_last(const std::string& path) const {
  if (thread_.joinable()) return Status(Errc::unsupported, "thumbnail: stop the renderer thread first");
  if (!have_last_) return Status(Errc::state, "thumbnail: none was rendered");
  return write_file_atomically(path, std::string(reinterpret_cast<const char*>(last_->png), last_->png_size_bytes));
}

}  // namespace visvol::app
