// Hidden-from and visible-to constraints for the executive: the hull of each
// point (rt/rope/field_forces.hpp, point_hull) is built on a thread of its
// own, never the real-time one, and handed to the loop whole.
//
//   loop thread                     builder thread
//   request(points)   --latest-->   builds both hulls into a free set
//   take() at a tick's start <--    publishes the set
//
// Both hand-offs are triple buffers (rt/base/handoff.hpp): wait-free for the
// loop, the newest value wins, and a set the loop has taken is never written
// until the loop takes another. The three sets are sized at create() (two
// hulls of the level's posts each); a build allocates only on the builder
// thread (the padded terrain and horizon of point_hull, transient).
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

#include "rt/base/handoff.hpp"
#include "rt/base/status.hpp"
#include "rt/rope/field_forces.hpp"
#include "storage/resident_pack.hpp"

namespace visvol::rt {

// What the loop asks for: either point may be absent (that constraint off).
struct HullRequest {
  std::uint64_t sequence = 0;  // the command's
  bool hidden = false, visible = false;
  double hidden_from_m[3] = {0, 0, 0};  // world metres of the pack's CRS
  double visible_to_m[3] = {0, 0, 0};
};

// A built pair of hulls; `has_*` false for a constraint that is off.
struct HullSet {
  std::uint64_t sequence = 0;
  bool has_hidden = false, has_visible = false;
  PointHull hidden, visible;
};

struct HullStats {
  std::uint64_t built = 0;     // sets published
  std::uint64_t failed = 0;    // requests refused by point_hull (the previous set stays)
  double last_build_ms = 0;    // wall time of the last build, refused or not
  std::string last_error;
};

class ConstraintHulls {
 public:
  // Reserves three sets of two hulls over `level`'s posts.
  static std::unique_ptr<ConstraintHulls> create(const storage::ResidentLevel& level);
  ~ConstraintHulls();
  ConstraintHulls(const ConstraintHulls&) = delete;
  ConstraintHulls& operator=(const ConstraintHulls&) = delete;

  // What create() reserves, and the most a build adds on the builder thread,
  // for a level of this geometry (bytes): for the memory budget.
  static std::uint64_t reserved_bytes(const fields::VolumeGeometry& g);
  static std::uint64_t build_bytes(const fields::VolumeGeometry& g);

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

  // Builds what `r` asks for into `out` (its hulls already sized). The
  // builder thread's work, public for tests.
  Status build(const HullRequest& r, HullSet& out) const;

 private:
  explicit ConstraintHulls(const storage::ResidentLevel& level);
  void run();
  void publish_set();

  const storage::ResidentLevel* level_;
  LatestValue<HullRequest> requests_;
  // triple buffer of sets, as LatestValue (which holds plain data only)
  std::array<HullSet, 3> sets_;
  unsigned back_ = 0, front_ = 2;
  std::atomic<unsigned> middle_{1};
  static constexpr unsigned kFresh = 4, kIndex = 3;

  std::atomic<std::uint64_t> built_{0}, failed_{0};
  std::atomic<std::int64_t> last_build_us_{0};
  std::atomic<std::uint64_t> refused_sequence_{0};
  mutable std::mutex mutex_;  // last_error_, stopping_
  std::condition_variable wake_;
  std::string last_error_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace visvol::rt
