// A pack tile's bytes held in memory of their own: read with pread and
// checked against the tile's checksum (Pack::read_tile) into anonymous pages.
// What a reader holds is then exactly what was checked, and a pack file cut
// short or rewritten in place later changes nothing it holds (a mapping of
// the file would raise SIGBUS, or change under the reader).
//
// Pages of their own, not the heap: an evicted tile's memory goes back to
// the system at once (munmap), and a lock (mlock) covers the tile alone.
// Allocates and reads: never from the real-time thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::storage {

class TileCopy {
 public:
  TileCopy() = default;  // empty
  // The tile read and checked, or why not (naming the pack and the tile).
  static Result<TileCopy> read(const Pack& pack, const TileEntry& tile);
  ~TileCopy();
  TileCopy(TileCopy&& other) noexcept;
  TileCopy& operator=(TileCopy&& other) noexcept;
  TileCopy(const TileCopy&) = delete;
  TileCopy& operator=(const TileCopy&) = delete;

  // The memory a copy of a tile of `tile_bytes` takes: whole pages.
  static std::uint64_t footprint(std::uint64_t tile_bytes);

  const std::uint8_t* data() const { return data_; }
  std::size_t bytes() const { return bytes_; }
  bool empty() const { return data_ == nullptr; }
  // Locks the copy in memory (mlock); "" or the system's reason it could not.
  std::string lock();

 private:
  std::uint8_t* data_ = nullptr;
  std::size_t bytes_ = 0;   // the tile's
  std::size_t mapped_ = 0;  // page-rounded
};

// Points a level at copies of its tiles: the one place that sets a
// PackLevel's tile pointers for the readers that hold copies (the tile pager,
// CachedLevel). Each copy is read and checked by TileCopy::read; `lock`, when
// given, is called on each copy made.
class LevelCopies {
 public:
  using Lock = std::function<void(TileCopy& copy, const TileEntry& tile)>;
  // The level with every tile pointer null (PackLevel::open_unset).
  static Result<PackLevel> unset(std::shared_ptr<const Pack> pack, int level);
  // Every height tile of the level copied into `out`, the level pointed at them.
  static Status copy_heights(PackLevel& level, std::vector<TileCopy>& out, const Lock& lock = {});
  // Brick b's F_p and terrain-force tiles copied into `visibility` and `tff`,
  // the level pointed at them; neither is changed when one cannot be read.
  static Status copy_brick(PackLevel& level, std::size_t b, TileCopy& visibility, TileCopy& tff, const Lock& lock = {});
  // Brick b's pointers cleared, then its copies freed.
  static void drop_brick(PackLevel& level, std::size_t b, TileCopy& visibility, TileCopy& tff);
  // The memory the copies of a level's height tiles take; of brick (bx, by)'s.
  static std::uint64_t heights_footprint(const Pack& pack, int level);
  static std::uint64_t brick_footprint(const Pack& pack, int level, int bx, int by);
};

}  // namespace visvol::storage
