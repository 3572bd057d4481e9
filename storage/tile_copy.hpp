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
#include <string>

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

}  // namespace visvol::storage
