// One level of detail of a pack read through copies (storage/tile_copy.hpp),
// for a thread outside the tile pager that samples a pack operators may
// replace under it (the console's path fitter): the level's heights are
// copied whole at open, its F_p and terrain-force bricks on first use, into a
// cache of at most `max_bricks` bricks (the least recently used goes first).
//
// A sampler level (fields/sampler.hpp): the values are exactly PackLevel's.
// A brick that cannot be read (the file cut short or changed since it was
// opened) reads as zeros (F_p 0, no terrain force) and is not read again;
// read_failures() counts such bricks, zero_reads() every value read as zero
// for want of its brick, and last_error() names the last one: a caller
// compares zero_reads() before and after its queries to know whether their
// figures stand.
//
// Not thread-safe (a read may fill the cache): one thread. Allocates.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"
#include "storage/pack_reader.hpp"
#include "storage/tile_copy.hpp"

namespace visvol::storage {

class CachedLevel {
 public:
  static constexpr int kDefaultBricks = 64;

  CachedLevel(CachedLevel&&) = default;
  CachedLevel& operator=(CachedLevel&&) = default;
  CachedLevel(const CachedLevel&) = delete;
  CachedLevel& operator=(const CachedLevel&) = delete;

  static Result<CachedLevel> open(std::shared_ptr<const Pack> pack, int level, int max_bricks = kDefaultBricks);

  const fields::VolumeGeometry& geometry() const { return level_.geometry(); }
  float post(int i, int j) const { return level_.post(i, j); }
  float voxel(int i, int j, int k) const { return ready(i, j) ? level_.voxel(i, j, k) : 0.0f; }
  fields::TffSample tff(int i, int j, int b) const { return ready(i, j) ? level_.tff(i, j, b) : fields::TffSample{}; }
  const fields::TffParams& tff_params() const { return level_.tff_params(); }

  const Pack& pack() const { return level_.pack(); }
  // Bricks that could not be read (each counted once), and the last reason.
  std::uint64_t read_failures() const { return failures_; }
  // Values read as zeros because their brick could not be read.
  std::uint64_t zero_reads() const { return zero_reads_; }
  const std::string& last_error() const { return last_error_.message(); }
  const Status& last_status() const { return last_error_; }
  // Bytes of tile copies held at most: the level's heights and the cache.
  static std::uint64_t bytes(const Pack& pack, int level, int max_bricks = kDefaultBricks);

 private:
  static constexpr int kUnread = -1, kUnreadable = -2;
  struct Slot {
    std::size_t brick = 0;
    std::uint64_t used = 0;  // the clock at its last read
    TileCopy visibility, tff;
  };
  explicit CachedLevel(PackLevel level) : level_(std::move(level)) {}
  // Whether the brick of column (i, j) is held, reading it first if need be.
  bool ready(int i, int j) const {
    const std::size_t b = static_cast<std::size_t>((j / kBrickPosts) * bricks_x_ + i / kBrickPosts);
    const int s = slot_of_[b];
    if (s >= 0) {
      slots_[static_cast<std::size_t>(s)].used = ++clock_;
      return true;
    }
    if (s == kUnread && load(b)) return true;
    ++zero_reads_;
    return false;
  }
  bool load(std::size_t brick) const;

  std::vector<TileCopy> heights_;
  // the level's height pointers into heights_, a brick's into its slot or
  // null; the cache below changes on reads
  mutable PackLevel level_;
  int bricks_x_ = 0;
  std::size_t max_slots_ = 0;
  mutable std::vector<Slot> slots_;
  mutable std::vector<int> slot_of_;  // per brick: its slot, kUnread or kUnreadable
  mutable std::uint64_t clock_ = 0;
  mutable std::uint64_t failures_ = 0;
  mutable std::uint64_t zero_reads_ = 0;
  mutable Status last_error_;
};

// A CachedLevel by reference: the sampler level a FieldSampler holds by
// value (a CachedLevel owns its copies and cannot be copied).
class CachedLevelRef {
 public:
  CachedLevelRef() = default;
  explicit CachedLevelRef(const CachedLevel& level) : level_(&level) {}
  const fields::VolumeGeometry& geometry() const { return level_->geometry(); }
  float post(int i, int j) const { return level_->post(i, j); }
  float voxel(int i, int j, int k) const { return level_->voxel(i, j, k); }
  fields::TffSample tff(int i, int j, int b) const { return level_->tff(i, j, b); }
  const fields::TffParams& tff_params() const { return level_->tff_params(); }

 private:
  const CachedLevel* level_ = nullptr;
};

}  // namespace visvol::storage
