// Hidden-from and visible-to constraints for the executive: the hull of each
// observer (rt/rope/point_hull_maker.hpp, PointHullMaker) is built on a thread of its
// own, never the real-time one, and folded by kind into the one hull the
// forces take (below every hidden-from hull, above every visible-to hull:
// the lowest and the highest of them post by post), then handed to the loop
// whole. Observers therefore cost build time (one hull each), not memory.
//
//   loop thread                     builder thread
//   request(points)   --latest-->   builds every hull into a free set
//   take() at a tick's start <--    publishes the set
//
// Both hand-offs are triple buffers (base/handoff.hpp): wait-free for the
// loop, the newest value wins, and a set the loop has taken is never written
// until the loop takes another. The three sets are sized at create(): each
// holds the two folded hulls of the level's posts. A request for more than
// `max_observers` observers (hidden-from and visible-to together, at most
// kMaxObserversPerKind of a kind) is refused, with a reason, by the executive
// before it gets here (and by build() again). A build allocates only on the
// builder thread (the level's padded terrain once a build, PointHullMaker;
// each observer's hull and horizon, transient, one observer at a time).
//
// Observers are as the planner takes them (rt/rope/path_check.hpp,
// ConstraintPoint): a point standing at or above the terrain, the eye
// `eye_height_m` above it, lifted onto the level's terrain where that is
// coarser and higher.
//
// Thread-safety: request() and take() on the loop thread only; stats() from
// any thread; start() and stop() from the owner.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "rt/rope/field_forces.hpp"
#include "storage/resident_pack.hpp"

namespace visvol::rt {

// Observers of one kind a request holds at most (as `visvol plan` takes them).
inline constexpr int kMaxObserversPerKind = 256;

// What the loop asks for: up to kMaxObserversPerKind observers of each kind
// (none: that kind off). Plain data, for LatestValue.
struct HullRequest {
  std::uint64_t sequence = 0;  // the command's
  int hidden_count = 0, visible_count = 0;
  double eye_height_m = 2.0;                           // the observers' eyes above their points
  double hidden_from_m[kMaxObserversPerKind][3] = {};  // standing points, world metres of the pack's CRS
  double visible_to_m[kMaxObserversPerKind][3] = {};

  // Appends an observer; false when that kind is full. Real-time safe.
  bool add_hidden_from(const Vec3& p) { return add(hidden_from_m, hidden_count, p); }
  bool add_visible_to(const Vec3& p) { return add(visible_to_m, visible_count, p); }
  int observers() const { return hidden_count + visible_count; }
  static Vec3 point(const double (&p)[3]) { return Vec3(p[0], p[1], p[2]); }

 private:
  static bool add(double (&to)[kMaxObserversPerKind][3], int& count, const Vec3& p) {
    if (count >= kMaxObserversPerKind) return false;
    double* d = to[count++];
    d[0] = p.x();
    d[1] = p.y();
    d[2] = p.z();
    return true;
  }
};

// A built set: the request it answers and the folded hull of each kind
// (null: no observer of that kind), pointing into `hulls` (two, reserved at
// create(), never reallocated).
struct HullSet {
  HullRequest request;
  std::vector<PointHull> hulls;
  const PointHull* hidden = nullptr;   // the lowest of the hidden-from hulls
  const PointHull* visible = nullptr;  // the highest of the visible-to hulls
  std::uint64_t sequence() const { return request.sequence; }
  int hidden_count() const { return request.hidden_count; }
  int visible_count() const { return request.visible_count; }
};

struct HullStats {
  std::uint64_t built = 0;   // sets published
  std::uint64_t failed = 0;  // requests refused (the previous set stays)
  double last_build_ms = 0;  // wall time of the last build, refused or not
  std::string last_error;
};

class ConstraintHulls {
 public:
  // The most observers a set may fold (kMaxObserversPerKind of each kind).
  static constexpr int kMaxObservers = 2 * kMaxObserversPerKind;

  // Reserves three sets of two hulls over `level`'s posts (none when
  // `max_observers` is 0: constraints off) for up to `max_observers`
  // (0..kMaxObservers) observers a request; invalid_argument outside that range.
  static Result<std::unique_ptr<ConstraintHulls>> create(const storage::ResidentLevel& level, int max_observers);
  ~ConstraintHulls();
  ConstraintHulls(const ConstraintHulls&) = delete;
  ConstraintHulls& operator=(const ConstraintHulls&) = delete;

  // What create() reserves for a level of this geometry and `max_observers`
  // (3 sets x 2 hulls x 4 bytes a post, none for 0 observers), and the most a
  // build adds on the builder thread (bytes): for the memory budget.
  static std::uint64_t reserved_bytes(const fields::VolumeGeometry& g, int max_observers);
  static std::uint64_t build_bytes(const fields::VolumeGeometry& g);
  // The most observers whose sets fit in `bytes`: kMaxObservers when the two
  // folded hulls of three sets fit, else 0.
  static int observers_within(const fields::VolumeGeometry& g, std::uint64_t bytes);

  int max_observers() const { return max_observers_; }

  void start();  // the builder thread
  void stop();   // joins it; a request not yet built is dropped

  // Loop thread, wait-free: replace the constraint set (the newest request
  // wins), and the newest built set, or null when none is new. The set stays
  // valid, and unchanged, until the next take().
  void request(const HullRequest& r);
  const HullSet* take();

  // The sequence of the last request the builder refused (0: none): the
  // loop stops waiting for that set (the previous one stays in force).
  std::uint64_t refused_sequence() const { return refused_sequence_.load(std::memory_order_acquire); }

  HullStats stats() const;
  const storage::ResidentLevel& level() const { return *level_; }

  // Builds what `r` asks for into `out`, one of this object's sets (or one
  // from reserve_set()); gives up (Errc::state) when superseded. The builder
  // thread's work, public for tests.
  Status build(const HullRequest& r, HullSet& out) const;
  // A set sized as create() sizes them (allocates).
  HullSet reserve_set() const;

 private:
  ConstraintHulls(const storage::ResidentLevel& level, int max_observers);
  void run();
  void publish_set();
  // A build in progress gives way (between observers) to a newer request or
  // to stop(): a set of many observers takes seconds to minutes.
  bool superseded() const { return abandon_.load(std::memory_order_relaxed) || requests_.fresh(); }

  const storage::ResidentLevel* level_;
  int max_observers_;
  LatestValue<HullRequest> requests_;
  // triple buffer of sets, as LatestValue (which holds plain data only)
  std::array<HullSet, 3> sets_;
  unsigned back_ = 0, front_ = 2;
  std::atomic<unsigned> middle_{1};
  static constexpr unsigned kFresh = 4, kIndex = 3;

  std::atomic<std::uint64_t> built_{0}, failed_{0};
  std::atomic<std::int64_t> last_build_us_{0};
  std::atomic<std::uint64_t> refused_sequence_{0};
  std::atomic<bool> abandon_{false};  // stop() asked: the build in progress ends
  mutable std::mutex mutex_;          // last_error_, stopping_
  std::condition_variable wake_;
  std::string last_error_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace visvol::rt
