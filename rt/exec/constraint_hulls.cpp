#include "rt/exec/constraint_hulls.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <optional>

#include "fields/hull_kernel.hpp"
#include "rt/rope/point_hull_maker.hpp"

namespace visvol::rt {

namespace {

constexpr std::uint64_t posts(const fields::VolumeGeometry& g) {
  return static_cast<std::uint64_t>(g.nx) * static_cast<std::uint64_t>(g.ny);
}

void size_hull(PointHull& h, const fields::VolumeGeometry& g) {
  h.nx = g.nx;
  h.ny = g.ny;
  h.origin_x = g.origin_x;
  h.origin_y = g.origin_y;
  h.spacing_m = g.spacing_m;
  h.height_m.assign(static_cast<std::size_t>(posts(g)), 0.0f);
}

// Copies a built hull into a reserved one of the same grid (no reallocation).
void copy_hull(const PointHull& from, PointHull& to) {
  std::copy(from.height_m.begin(), from.height_m.end(), to.height_m.begin());
}

}  // namespace

ConstraintHulls::ConstraintHulls(const storage::ResidentLevel& level, int max_observers)
    : level_(&level), max_observers_(max_observers) {
  for (HullSet& s : sets_) s = reserve_set();
}

Result<std::unique_ptr<ConstraintHulls>> ConstraintHulls::create(const storage::ResidentLevel& level,
                                                                 int max_observers) {
  if (max_observers < 0 || max_observers > kMaxObservers) {
    return invalid_argument("constraint hulls: " + std::to_string(max_observers) + " observers, not 0.." +
                            std::to_string(kMaxObservers));
  }
  return std::unique_ptr<ConstraintHulls>(new ConstraintHulls(level, max_observers));
}

ConstraintHulls::~ConstraintHulls() { stop(); }

HullSet ConstraintHulls::reserve_set() const {
  HullSet s;
  s.hulls.resize(max_observers_ > 0 ? 2 : 0);  // the folded hidden-from and visible-to hulls
  for (PointHull& h : s.hulls) size_hull(h, level_->geometry());
  return s;
}

std::uint64_t ConstraintHulls::reserved_bytes(const fields::VolumeGeometry& g, int max_observers) {
  const std::uint64_t hulls = max_observers > 0 ? 2 : 0;
  return 3 * hulls * posts(g) * sizeof(float);
}

int ConstraintHulls::observers_within(const fields::VolumeGeometry& g, std::uint64_t bytes) {
  return reserved_bytes(g, 1) <= bytes ? kMaxObservers : 0;
}

std::uint64_t ConstraintHulls::build_bytes(const fields::VolumeGeometry& g) {
  // PointHullMaker (the heightfield and its padding), the horizon over the
  // square of the largest radius, the hull
  const int radius = std::max(g.nx, g.ny) - 1;
  const std::uint64_t side = 2 * static_cast<std::uint64_t>(radius) + 1;
  return PointHullMaker::bytes(g.nx, g.ny) + (posts(g) + side * side) * sizeof(float);
}

void ConstraintHulls::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable()) return;
  stopping_ = false;
  abandon_.store(false, std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
}

void ConstraintHulls::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!thread_.joinable()) return;
    stopping_ = true;
  }
  abandon_.store(true, std::memory_order_relaxed);
  wake_.notify_all();
  thread_.join();
}

void ConstraintHulls::request(const HullRequest& r) { requests_.write(r); }

const HullSet* ConstraintHulls::take() {
  if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return nullptr;
  const unsigned prev = middle_.exchange(front_, std::memory_order_acq_rel);
  front_ = prev & kIndex;
  return &sets_[front_];
}

void ConstraintHulls::publish_set() {
  const unsigned prev = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
  back_ = prev & kIndex;
}

HullStats ConstraintHulls::stats() const {
  HullStats s;
  s.built = built_.load(std::memory_order_relaxed);
  s.failed = failed_.load(std::memory_order_relaxed);
  s.last_build_ms = static_cast<double>(last_build_us_.load(std::memory_order_relaxed)) * 1e-3;
  std::lock_guard<std::mutex> lock(mutex_);
  s.last_error = last_error_;
  return s;
}

Status ConstraintHulls::build(const HullRequest& r, HullSet& out) const {
  const int n = r.hidden_count + r.visible_count;
  if (r.hidden_count < 0 || r.visible_count < 0 || r.hidden_count > kMaxObserversPerKind ||
      r.visible_count > kMaxObserversPerKind || n > max_observers_ || (n > 0 && out.hulls.size() < 2)) {
    return invalid_argument(std::to_string(r.hidden_count) + " hidden-from and " + std::to_string(r.visible_count) +
                            " visible-to points: this console takes " + std::to_string(max_observers_) + " (at most " +
                            std::to_string(kMaxObserversPerKind) + " of a kind)");
  }
  std::optional<PointHullMaker> make;  // the level's terrain padded once for all of them
  if (n > 0) make.emplace(*level_);
  for (int k = 0; k < n; ++k) {
    if (k > 0 && superseded()) return Status(Errc::state, "hulls: superseded by a newer request, or stopped");
    const bool hidden = k < r.hidden_count;
    const double(&p)[3] = hidden ? r.hidden_from_m[k] : r.visible_to_m[k - r.hidden_count];
    const Vec3 eye = eye_on_level(*level_, HullRequest::point(p) + Vec3(0, 0, r.eye_height_m));
    Result<PointHull> h = (*make)(eye, hidden ? "hidden-from point" : "visible-to point");
    if (!h.ok()) return h.status();
    // the first of a kind is copied, the others folded in (into the
    // reserved hull: no reallocation)
    PointHull& kind_hull = out.hulls[hidden ? 0 : 1];
    if (k == 0 || k == r.hidden_count) {
      copy_hull(*h, kind_hull);
    } else {
      fold_hull(kind_hull, *h, hidden);
    }
  }
  out.hidden = r.hidden_count > 0 ? &out.hulls[0] : nullptr;
  out.visible = r.visible_count > 0 ? &out.hulls[1] : nullptr;
  out.request = r;
  return Status::ok_status();
}

void ConstraintHulls::run() {
  pthread_setname_np(pthread_self(), "visvol-hulls");
  // The loop cannot wake this thread (it makes no system call but its
  // sleep): requests are polled.
  constexpr auto kPoll = std::chrono::milliseconds(20);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, kPoll, [this] { return stopping_; });
    if (stopping_) break;
    lock.unlock();
    if (const HullRequest* r = requests_.take()) {
      const auto t0 = std::chrono::steady_clock::now();
      Status s;
      try {
        s = build(*r, sets_[back_]);
      } catch (const std::exception& e) {  // bad_alloc on a level too large for the memory left
        s = Status(Errc::resource, std::string("building the hulls: ") + e.what());
      }
      last_build_us_.store(
          std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0).count(),
          std::memory_order_relaxed);
      if (s.ok()) {
        publish_set();
        built_.fetch_add(1, std::memory_order_relaxed);
      } else if (superseded()) {
        // given up for a newer request (built next) or for stop(): not refused
      } else {
        refused_sequence_.store(r->sequence, std::memory_order_release);
        failed_.fetch_add(1, std::memory_order_relaxed);
        std::lock_guard<std::mutex> error_lock(mutex_);
        last_error_ = s.message();
      }
    }
    lock.lock();
  }
}

}  // namespace visvol::rt
