// Resident tiles: the part of a field pack the real-time thread may read,
// kept in memory within a budget.
//
// Tiles are copied out of the pack file (storage/tile_copy.hpp: pread, then
// the checksum) into memory of their own, never read through a mapping: a
// pack file cut short or rewritten under a running console changes nothing
// the real-time thread reads (a brick the pager cannot read any more stays
// out, counted and named). A pager thread (not real-time) keeps resident and
// locked (mlock), what the rope needs:
//   - the terrain heights of every level of detail, always;
//   - every field brick (F_p and terrain force, 16 x 16 columns) of the
//     coarsest level, always: the floor every lookup can fall back to;
//   - the bricks of the finer levels around the rope's bounding box plus a
//     margin, coarser levels first, nearest bricks first, while the budget
//     lasts; bricks far from the rope are evicted (their copies freed).
// Each brick's checksum is checked on its copy; a corrupt or unreadable one
// stays out for good (counted once and named), so lookups there fall back.
//
// The real-time thread reads through ResidentLevel, a sampler level
// (fields/sampler.hpp) that reads a brick only when it is resident and
// otherwise samples the next coarser level at the same world point: it never
// touches a page that is not locked, so it never waits on the disk. It tells
// the pager where the rope is (set_focus) and when it has finished a tick
// (tick_done): a brick is unmapped only after the real-time thread has passed
// two tick boundaries since the brick was marked absent, so no read is ever
// in flight on an evicted brick. The pack's mapping, if it has one, is never
// read here (the pack may be opened with PackAccess::inspect).
//
// Ownership: shares the Pack; owns the pager thread and the locks.
// Thread-safety: level(), set_focus(), tick_done() from the real-time thread
// (wait-free, no allocation); everything else from one controlling thread.
// Cost: the pager's passes are O(bricks near the rope) plus the page-ins.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "base/handoff.hpp"
#include "base/status.hpp"
#include "fields/sampler.hpp"
#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"
#include "storage/pack_reader.hpp"
#include "storage/tile_copy.hpp"

namespace visvol::storage {

// An axis-aligned box in world metres (the pack's CRS).
struct WorldBox {
  double x0_m = 0, y0_m = 0, x1_m = 0, y1_m = 0;  // min and max corners
};

struct ResidentConfig {
  std::uint64_t budget_bytes = 256ull << 20;  // tile bytes resident at most, the minimum included
  double margin_m = 1000.0;                   // kept around the rope's bounding box
  double poll_interval_s = 0.01;              // pager passes
  bool lock = true;                           // mlock resident tiles (false: prefault only)
};
Status validate(const ResidentConfig& config);

struct ResidentStats {
  std::uint64_t budget_bytes = 0;
  std::uint64_t minimum_bytes = 0;   // heights of every level + the coarsest level's bricks
  std::uint64_t resident_bytes = 0;  // tiles made resident now (accounted, page-rounded)
  std::uint64_t pack_bytes = 0;
  std::uint64_t passes = 0;
  std::uint64_t bricks_loaded = 0;
  std::uint64_t bricks_evicted = 0;
  std::uint64_t lock_failures = 0;   // tiles prefaulted but not locked (no CAP_IPC_LOCK)
  std::uint64_t corrupt_bricks = 0;  // bricks unreadable or failing their checksum (each once): never resident
  std::uint64_t budget_short = 0;    // passes that could not hold every wanted brick
  std::vector<std::uint32_t> resident_bricks;  // per level
  std::vector<std::uint32_t> brick_counts;     // per level
  std::string last_error;                      // the last corrupt tile or lock failure, named
};

class ResidentPack;

// A PackLevel by reference: a sampler level that is cheap to copy.
class PackLevelRef {
 public:
  PackLevelRef() = default;
  explicit PackLevelRef(const PackLevel& level) : level_(&level) {}
  const fields::VolumeGeometry& geometry() const { return level_->geometry(); }
  float post(int i, int j) const { return level_->post(i, j); }
  float voxel(int i, int j, int k) const { return level_->voxel(i, j, k); }
  fields::TffSample tff(int i, int j, int b) const { return level_->tff(i, j, b); }
  PackLevel::Column column(int i, int j) const { return level_->column(i, j); }
  const fields::TffParams& tff_params() const { return level_->tff_params(); }

 private:
  const PackLevel* level_ = nullptr;
};

// One level of detail as the real-time thread samples it (a sampler Level:
// geometry, post, voxel, tff, tff_params). Copyable view: pointers only.
class ResidentLevel {
 public:
  const fields::VolumeGeometry& geometry() const { return level_->geometry(); }
  float post(int i, int j) const { return level_->post(i, j); }  // heights are always resident
  float voxel(int i, int j, int k) const;
  fields::TffSample tff(int i, int j, int b) const;
  const fields::TffParams& tff_params() const { return level_->tff_params(); }
  // Whether the brick holding column (i, j) is resident.
  bool resident(int i, int j) const;
  // Whether every brick holding columns [i0, i1] x [j0, j1] is resident.
  bool resident(int i0, int j0, int i1, int j1) const;
  int level() const { return level_->level(); }
  const ResidentLevel* coarser() const { return coarser_; }

 private:
  friend class ResidentPack;
  friend class ResidentSampler;
  // Its bricks that are not resident have no bytes: for the sampler, which
  // checks residency first.
  const PackLevel& pack_level() const { return *level_; }
  const PackLevel* level_ = nullptr;
  const std::atomic<std::uint8_t>* state_ = nullptr;  // per brick: 1 resident
  int bricks_x_ = 0;
  const ResidentLevel* coarser_ = nullptr;           // null: the coarsest, always resident
  std::atomic<std::uint64_t>* fallbacks_ = nullptr;  // lookups served by a coarser level
};

// The sampler the real-time thread uses (the interface of
// fields::FieldSampler): each query is answered by the finest level, from
// the one given down, whose bricks around the point are all resident, read
// directly; heights come from the level given (always resident). Cheaper
// than sampling a ResidentLevel, whose every missing voxel is interpolated
// from the coarser level. Where residency changes between neighbouring
// bricks the field steps from one level's values to the next one's.
class ResidentSampler {
 public:
  explicit ResidentSampler(const ResidentLevel& level);
  const ResidentLevel& level() const { return *level_; }
  double height(double x, double y) const { return samplers_[0].height(x, y); }
  double visibility(double x, double y, double z) const { return pick(x, y).visibility(x, y, z); }
  Eigen::Vector3d gradient(double x, double y, double z) const { return pick(x, y).gradient(x, y, z); }
  fields::TffSample terrain_force(double x, double y, double z) const { return pick(x, y).terrain_force(x, y, z); }
  // height(), gradient() and terrain_force() with one pick of the level
  // (fields::FieldSampler::sample): exactly what the three calls return.
  fields::PointSample sample(double x, double y, double z, bool with_gradient, bool with_terrain_force) const;

 private:
  using Sampler = fields::FieldSampler<PackLevelRef>;
  const Sampler& pick(double x, double y) const {
    Sampler::Cell unused;
    return samplers_[pick(x, y, unused)];
  }
  // The finest level whose bricks around (x, y) are all resident, and the
  // point's cell on it (and on the level given, where `finest` is set).
  int pick(double x, double y, Sampler::Cell& cell, Sampler::Cell* finest = nullptr) const;
  const ResidentLevel* level_;
  const ResidentLevel* chain_[kMaxLodLevels] = {};
  Sampler samplers_[kMaxLodLevels];
  int count_ = 0;
};

class ResidentPack {
 public:
  // Copies and locks the heights of every level and the coarsest level's
  // bricks (checking their checksums). Fails, saying what the minimum is,
  // when the budget cannot hold it.
  static Result<std::unique_ptr<ResidentPack>> create(std::shared_ptr<const Pack> pack, const ResidentConfig& config);
  ~ResidentPack();  // stops the pager; the copies are freed
  ResidentPack(const ResidentPack&) = delete;
  ResidentPack& operator=(const ResidentPack&) = delete;

  int level_count() const { return static_cast<int>(levels_.size()); }
  // Real-time side.
  const ResidentLevel& level(int l) const { return views_[static_cast<std::size_t>(l)]; }
  void set_focus(const WorldBox& box) { focus_.write(box); }
  // The count, the pager's evictions and its reading of the count, and the
  // readers' residency checks are all sequentially consistent (one total
  // order, StoreLoad included; no fences, which ThreadSanitizer cannot
  // follow): a tick that starts after a count the pager did not see yet sees
  // every eviction made before the pager read the count.
  void tick_done() { epoch_.fetch_add(1, std::memory_order_seq_cst); }
  // Lookups that fell back to a coarser level, all levels (any thread).
  std::uint64_t fallbacks() const;

  // Whether evictions must wait for tick_done() calls: set while a real-time
  // thread reads, cleared after it has stopped.
  void set_reader_active(bool active) { reader_active_.store(active, std::memory_order_release); }

  // The pager: one pass now (start-up, tests), or a thread every poll interval.
  Status update();
  void start_pager();
  void stop_pager();

  const Pack& pack() const { return *pack_; }
  const ResidentConfig& config() const { return config_; }
  ResidentStats stats() const;

 private:
  struct Brick {
    std::uint64_t bytes;  // of its copies (F_p and terrain force), whole pages
  };
  struct LevelState {
    int bricks_x = 0, bricks_y = 0;
    std::vector<Brick> bricks;
    std::vector<TileCopy> copies;                        // brick b: 2 b visibility, 2 b + 1 terrain force
    std::vector<std::uint8_t> refused;                   // 1: unreadable or corrupt, never tried again
    std::unique_ptr<std::atomic<std::uint8_t>[]> state;  // 1: resident
    std::vector<std::uint8_t> target;                    // pager's plan of this pass
    std::atomic<std::uint64_t> fallbacks{0};
  };

  ResidentPack(std::shared_ptr<const Pack> pack, const ResidentConfig& config);
  Status init();
  LevelCopies::Lock lock_copy();                    // locks each copy where the config asks
  Status load_brick(int level, std::size_t brick);  // copies it and points the level at them
  void drop_brick(int level, std::size_t brick);
  bool wait_for_readers();
  void drop_evicted();  // after wait_for_readers()
  void plan(const WorldBox& box, std::uint64_t budget_left);
  void pager_loop();

  std::shared_ptr<const Pack> pack_;
  ResidentConfig config_;
  std::vector<PackLevel> levels_;  // their tile pointers: into the copies below, or null
  std::vector<TileCopy> heights_;  // every level's height tiles
  std::vector<std::unique_ptr<LevelState>> state_;
  std::vector<std::pair<int, std::size_t>> evicted_;  // marked absent, copies not yet dropped
  std::vector<ResidentLevel> views_;

  LatestValue<WorldBox> focus_;
  WorldBox last_focus_{};
  bool have_focus_ = false;
  std::atomic<std::uint64_t> epoch_{0};
  std::atomic<bool> reader_active_{false};

  std::mutex update_mutex_;  // one pass at a time (pager thread or update())
  mutable std::mutex stats_mutex_;
  ResidentStats stats_;
  std::atomic<bool> stop_{false};
  std::thread pager_;
};

}  // namespace visvol::storage
