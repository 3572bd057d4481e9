#include "app/flyable_path.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "rt/rope/path_metrics.hpp"

namespace visvol::app {

Result<std::unique_ptr<PathFitter>> PathFitter::create(std::shared_ptr<const storage::Pack> pack,
                                                       const rt::VehicleEnvelope& vehicle, int fc_samples) {
  VISVOL_RETURN_IF_ERROR(rt::validate(vehicle));
  if (fc_samples < 2) return invalid_argument("flyable path: fc_samples must be at least 2");
  // the console verified the pack's tiles when it opened it
  Result<storage::PackLevel> level = storage::PackLevel::open(std::move(pack), 0, storage::TileCheck::deferred);
  if (!level.ok()) return level.status();
  std::unique_ptr<PathFitter> f(new PathFitter());
  f->vehicle_ = vehicle;
  f->fc_samples_ = fc_samples;
  f->finest_ = std::make_unique<storage::PackLevel>(std::move(*level));
  f->top_m_ = f->finest_->geometry().top_m();
  f->field_ = std::make_unique<rt::FieldForces<storage::PackLevel>>(*f->finest_, rt::ForceGains{});
  f->terrain_ = rt::level_terrain(*f->finest_);
  return f;
}

rt::VehicleEnvelope PathFitter::envelope(const rt::ForceGains& g) const {
  rt::VehicleEnvelope e = vehicle_;
  e.clearance_m = g.clearance_m;
  e.max_agl_m = g.max_agl_m;
  e.max_altitude_m = g.max_altitude_m;
  return e;
}

rt::EnvelopeFit PathFitter::fit(const rt::Vec3* vertices, int count, const rt::ForceGains& gains) const {
  rt::EnvelopeFitSpec spec;
  spec.envelope = envelope(gains);
  spec.top_m = top_m_;
  spec.max_points = dds::kMaxPathVertices;
  return rt::fit_to_envelope(std::vector<rt::Vec3>(vertices, vertices + count), spec, terrain_);
}

void PathFitter::describe(const std::vector<rt::Vec3>& path, dds::PathSample& out) const {
  const int n = static_cast<int>(std::min(path.size(), dds::kMaxPathVertices));
  double lowest = INFINITY;
  for (int k = 0; k < n; ++k) {
    const rt::Vec3& x = path[static_cast<std::size_t>(k)];
    dds::PathVertex& v = out.vertices[k];
    v.position = {x.x(), x.y(), x.z()};
    v.visibility = field_->visibility(x);
    v.clearance_m = x.z() - field_->terrain_height_m(x.x(), x.y());
    lowest = std::min(lowest, v.clearance_m);
  }
  out.vertex_count = static_cast<std::uint32_t>(n);
  out.min_clearance_m = lowest;
  out.f_c = n >= 2 ? rt::path_fc(path.data(), n, *field_, fc_samples_) : 0.0;
  double length = 0;
  for (int k = 1; k < n; ++k) length += (path[static_cast<std::size_t>(k)] - path[static_cast<std::size_t>(k - 1)]).norm();
  out.length_m = length;
}

// ---- the thread -------------------------------------------------------------

FlyablePath::FlyablePath(std::unique_ptr<PathFitter> fitter, LatestValue<dds::PathSample>* to_publisher,
                         LatestValue<dds::PathSample>* to_renderer, double poll_s)
    : fitter_(std::move(fitter)),
      to_publisher_(to_publisher),
      to_renderer_(to_renderer),
      poll_s_(poll_s),
      out_(std::make_unique<dds::PathSample>()) {
  rope_.reserve(dds::kMaxPathVertices);
}

Result<std::unique_ptr<FlyablePath>> FlyablePath::start(std::unique_ptr<PathFitter> fitter,
                                                        LatestValue<dds::PathSample>* to_publisher,
                                                        LatestValue<dds::PathSample>* to_renderer, double poll_s) {
  if (!fitter) return invalid_argument("flyable path: no fitter");
  if (!(poll_s > 0 && poll_s <= 1)) return invalid_argument("flyable path: poll interval outside (0, 1] s");
  std::unique_ptr<FlyablePath> f(new FlyablePath(std::move(fitter), to_publisher, to_renderer, poll_s));
  f->thread_ = std::thread([p = f.get()] { p->run(); });
  return f;
}

FlyablePath::~FlyablePath() { stop(); }

void FlyablePath::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

FlyableStats FlyablePath::stats() const {
  return {fitted_.load(std::memory_order_relaxed), unflyable_.load(std::memory_order_relaxed)};
}

void FlyablePath::run() {
  rt::ForceGains gains;
  bool have_gains = false;
  const auto poll = std::chrono::duration<double>(poll_s_);
  while (!stop_.load(std::memory_order_acquire)) {
    if (const rt::ForceGains* g = gains_.take()) gains = *g, have_gains = true;
    // the gains are handed off before their path: a path never comes first
    if (const dds::PathSample* p = rope_paths_.take(); p != nullptr && have_gains) send(*p, gains);
    std::this_thread::sleep_for(poll);
  }
}

void FlyablePath::send(const dds::PathSample& rope, const rt::ForceGains& gains) {
  rope_.clear();
  for (std::uint32_t k = 0; k < rope.vertex_count && k < dds::kMaxPathVertices; ++k) {
    const dds::WorldPoint& w = rope.vertices[k].position;
    rope_.emplace_back(w.x_m, w.y_m, w.z_m);
  }
  if (rope_.size() < 2) return;
  const rt::EnvelopeFit fit = fitter_->fit(rope_.data(), static_cast<int>(rope_.size()), gains);
  if (fit.path.size() < 2) return;
  dds::PathSample& out = *out_;
  // the header as the rope's: its run, its time, its state of rest
  out.sequence = rope.sequence;
  out.stamp_ns = rope.stamp_ns;
  std::memcpy(out.pack_id, rope.pack_id, sizeof out.pack_id);
  out.objective = rope.objective;
  out.converged = rope.converged;
  fitter_->describe(fit.path, out);
  for (LatestValue<dds::PathSample>* sink : {to_publisher_, to_renderer_}) {
    if (sink != nullptr) sink->write(out);
  }
  fitted_.fetch_add(1, std::memory_order_relaxed);
  if (!fit.feasible) unflyable_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace visvol::app
