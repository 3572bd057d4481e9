#include "app/flyable_path.hpp"

#include <pthread.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>

#include "rt/rope/path_check.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/point_hull_maker.hpp"

namespace visvol::app {

Result<std::unique_ptr<PathFitter>> PathFitter::create(std::shared_ptr<const storage::Pack> pack,
                                                       const rt::VehicleEnvelope& vehicle, int fc_samples,
                                                       int max_observers) {
  VISVOL_RETURN_IF_ERROR(rt::validate(vehicle));
  if (fc_samples < 2) return invalid_argument("flyable path: fc_samples must be at least 2");
  // every tile checked once here (read with pread), and each brick again as
  // it is copied: the fitter reads level 0 outside the pager
  VISVOL_RETURN_IF_ERROR(pack->verify_level(0));
  Result<storage::CachedLevel> level = storage::CachedLevel::open(std::move(pack), 0);
  if (!level.ok()) return level.status();
  std::unique_ptr<PathFitter> f(new PathFitter());
  f->bounds_ = storage::planning_bounds(level->pack());
  f->vehicle_ = vehicle;
  f->fc_samples_ = fc_samples;
  f->finest_ = std::make_unique<storage::CachedLevel>(std::move(*level));
  f->top_m_ = f->finest_->geometry().top_m();
  f->field_ = std::make_unique<rt::FieldForces<storage::CachedLevelRef>>(storage::CachedLevelRef(*f->finest_),
                                                                         rt::ForceGains{});
  f->terrain_ = rt::level_terrain(*f->finest_);
  f->observers_allowed_ = max_observers > 0;
  return f;
}

std::uint64_t PathFitter::bytes(const storage::Pack& pack, int observers) {
  const fields::VolumeGeometry g = pack.geometry(0);
  const auto posts = static_cast<std::uint64_t>(g.nx) * static_cast<std::uint64_t>(g.ny);
  return storage::CachedLevel::bytes(pack, 0) +
         posts * sizeof(float) * static_cast<std::uint64_t>(observers > 0 ? 3 : 1);
}

void PathFitter::set_observers(const rt::HullRequest& r) {
  if (r.sequence == observers_sequence_) return;
  hidden_.reset();
  visible_.reset();
  below_.clear();
  above_.clear();
  std::optional<rt::PointHullMaker> make;  // the terrain padded once for the set
  if (observers_allowed_ && r.hidden_count + r.visible_count > 0) make.emplace(*finest_);
  auto add = [&](const double(&p)[3], bool hidden) {
    if (!make) return void(++hull_failures_);
    // on its post, as the executive's hull builder puts it (a point accepted
    // on the bilinear terrain may be under the nearest post)
    const rt::Vec3 eye = rt::eye_on_level(*finest_, rt::HullRequest::point(p) + rt::Vec3(0, 0, r.eye_height_m));
    Result<rt::PointHull> h = (*make)(eye, hidden ? "hidden-from" : "visible-to");
    if (!h.ok()) return void(++hull_failures_);
    std::optional<rt::PointHull>& folded = hidden ? hidden_ : visible_;
    if (folded) {
      rt::fold_hull(*folded, *h, hidden);
    } else {
      folded = std::move(*h);
    }
  };
  for (int k = 0; k < r.hidden_count; ++k) add(r.hidden_from_m[k], true);
  for (int k = 0; k < r.visible_count; ++k) add(r.visible_to_m[k], false);
  if (hidden_) below_.push_back(&*hidden_);
  if (visible_) above_.push_back(&*visible_);
  // last: a build that threw (out of memory) is tried again with the next fit
  observers_sequence_ = r.sequence;
}

rt::VehicleEnvelope PathFitter::envelope(const rt::ForceGains& g) const {
  rt::VehicleEnvelope e = vehicle_;
  e.clearance_m = g.clearance_m;
  e.max_agl_m = g.max_agl_m;
  e.max_altitude_m = g.max_altitude_m;
  return e;
}

rt::EnvelopeFit PathFitter::fit(const rt::Vec3* vertices, int count, const rt::ForceGains& gains) const {
  for (int i = 0; i < count; ++i) {
    if (!vertices[i].allFinite()) return {};
  }
  std::vector<rt::Vec3> path;
  const int keep = std::min(count, static_cast<int>(msg::kMaxPathVertices));
  for (int k = 0; k < keep; ++k) {
    // evenly spaced, both ends kept (as the executive thins what it sends)
    const int i = keep == count ? k : static_cast<int>(std::lround(static_cast<double>(k) * (count - 1) / (keep - 1)));
    path.push_back(vertices[i]);
  }
  if (path.size() < 2) return {};
  rt::EnvelopeFitSpec spec;
  spec.envelope = envelope(gains);
  spec.top_m = top_m_;
  spec.planning_bounds = bounds_;
  spec.max_points = msg::kMaxPathVertices;
  spec.below = below_;
  spec.above = above_;
  return rt::fit_to_envelope(path, spec, terrain_);
}

bool PathFitter::describe(const std::vector<rt::Vec3>& path, msg::PathSample& out) const {
  const std::uint64_t zeros = finest_->zero_reads();
  const int n = static_cast<int>(std::min(path.size(), msg::kMaxPathVertices));
  double lowest = INFINITY;
  for (int k = 0; k < n; ++k) {
    const rt::Vec3& x = path[static_cast<std::size_t>(k)];
    msg::PathVertex& v = out.vertices[k];
    v.position = {x.x(), x.y(), x.z()};
    v.visibility = field_->visibility(x);
    v.clearance_m = x.z() - field_->terrain_height_m(x.x(), x.y());
    lowest = std::min(lowest, v.clearance_m);
  }
  out.vertex_count = static_cast<std::uint32_t>(n);
  out.min_clearance_m = lowest;
  out.f_c = n >= 2 ? rt::path_fc(path.data(), n, *field_, fc_samples_) : 0.0;
  double length = 0;
  for (int k = 1; k < n; ++k)
    length += (path[static_cast<std::size_t>(k)] - path[static_cast<std::size_t>(k - 1)]).norm();
  out.length_m = length;
  if (finest_->zero_reads() == zeros) return true;
  // unread bricks read as zeros: no figure of F_p stands
  out.f_c = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < n; ++k) out.vertices[k].visibility = std::numeric_limits<double>::quiet_NaN();
  return false;
}

// ---- the thread -------------------------------------------------------------

FlyablePath::FlyablePath(std::unique_ptr<PathFitter> fitter, LatestValue<msg::PathSample>* to_publisher,
                         LatestValue<msg::PathSample>* to_renderer, double poll_s)
    : fitter_(std::move(fitter)),
      to_publisher_(to_publisher),
      to_renderer_(to_renderer),
      poll_s_(poll_s),
      out_(std::make_unique<msg::PathSample>()) {
  rope_.reserve(msg::kMaxPathVertices);
}

Result<std::unique_ptr<FlyablePath>> FlyablePath::start(std::unique_ptr<PathFitter> fitter,
                                                        LatestValue<msg::PathSample>* to_publisher,
                                                        LatestValue<msg::PathSample>* to_renderer, double poll_s) {
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
  return {fitted_.load(std::memory_order_relaxed), unflyable_.load(std::memory_order_relaxed),
          failed_.load(std::memory_order_relaxed), hull_failures_.load(std::memory_order_relaxed)};
}

void FlyablePath::run() {
  pthread_setname_np(pthread_self(), "visvol-flyable");
  const auto poll = std::chrono::duration<double>(poll_s_);
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    // the last path handed off is sent too, before stopping
    if (const rt::LimitedPath* p = rope_paths_.take()) {
      try {
        send(*p);
      } catch (const std::exception&) {  // memory: this path is not sent, the last one stands
        failed_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    if (stopping) return;
    std::this_thread::sleep_for(poll);
  }
}

void FlyablePath::send(const rt::LimitedPath& limited) {
  const msg::PathSample& rope = limited.path;
  const rt::PathLimits& limits = limited.limits;
  rope_.clear();
  for (std::uint32_t k = 0; k < rope.vertex_count && k < msg::kMaxPathVertices; ++k) {
    const msg::WorldPoint& w = rope.vertices[k].position;
    rope_.emplace_back(w.x_m, w.y_m, w.z_m);
  }
  if (rope_.size() < 2) return;
  fitter_->set_observers(limits.observers);
  hull_failures_.store(fitter_->hull_failures(), std::memory_order_relaxed);
  const rt::EnvelopeFit fit = fitter_->fit(rope_.data(), static_cast<int>(rope_.size()), limits.gains);
  if (fit.path.size() < 2) return;
  msg::PathSample& out = *out_;
  // the header as the rope's: its run, its time, its state of rest
  out.sequence = rope.sequence;
  out.stamp_ns = rope.stamp_ns;
  std::memcpy(out.pack_id, rope.pack_id, sizeof out.pack_id);
  out.objective = rope.objective;
  out.converged = rope.converged;
  out.mode = rope.mode;  // spool mode: a rope still being paid out reaches only its free end
  out.spool_paid_out_m = rope.spool_paid_out_m;
  out.inside_envelope = fit.feasible;
  if (!fitter_->describe(fit.path, out)) {  // the pack changed under the session: no figures to trust
    failed_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  for (LatestValue<msg::PathSample>* sink : {to_publisher_, to_renderer_}) {
    if (sink != nullptr) sink->write(out);
  }
  fitted_.fetch_add(1, std::memory_order_relaxed);
  if (!fit.feasible) unflyable_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace visvol::app
