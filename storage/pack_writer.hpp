// Writes a field pack (see pack_format.hpp) tile by tile.
//
// Every tile's place in the file is known at create(), so tiles can arrive in
// any order as the builders produce them and nothing larger than a tile is
// held. The file is written under a temporary name; finish() writes the tables,
// the metadata and the header, fsyncs and renames it into place. Destroying
// an unfinished writer removes the temporary: a killed or failed build leaves
// the old pack (or none), never a torn one.
//
// Offline only (blocking I/O). One thread at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "io/atomic_file.hpp"
#include "storage/crc32c.hpp"
#include "storage/pack_format.hpp"

namespace visvol::storage {

struct PackLayout {
  std::vector<LevelEntry> levels;  // first_tile is filled in by create()
  VisibilityEncoding encoding = VisibilityEncoding::uint16;
  int band_levels = 24;
  double band_offset_m = 100.0;
};

// Checks a layout's sizes before anything is written.
Status validate(const PackLayout& layout);

// Payload size of a tile of `layer` at `level` of a layout (before page padding).
std::size_t payload_bytes(const PackLayout& layout, int level, Layer layer);

// Where every tile of a layout lies in the file: entries in file order
// (level, layer, ty, tx; checksums zero), each tile on its own pages after the
// header, then the tables. The same for every process that places the same
// layout, so processes of one build can each write their own tiles.
struct TilePlacement {
  PackLayout layout;  // first_tile filled in
  std::vector<TileEntry> tiles;
  std::uint64_t tables_offset = 0;  // the end of the tiles

  std::size_t payload_bytes(int level, Layer layer) const { return storage::payload_bytes(layout, level, layer); }
  // The entry of a tile, after checking the level, the tile and the payload size.
  Result<std::size_t> find(int level, Layer layer, int tx, int ty, std::size_t bytes) const;
  // Checks a tile (find), then writes it as stored (the payload, then zeros
  // to the end of its pages) through `write_at(data, bytes, offset)`: its
  // entry and the checksum of its stored bytes.
  struct Stored {
    std::size_t index = 0;
    std::uint32_t crc32c = 0;
  };
  template <class WriteAt>
  Result<Stored> store(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes,
                       WriteAt&& write_at) const;
};
Result<TilePlacement> place_tiles(PackLayout layout);

// Receives a pack's tiles, in any order, from one thread.
class TileSink {
 public:
  virtual ~TileSink() = default;
  // `bytes` must equal the layout's payload size of the tile.
  virtual Status write_tile(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes) = 0;
};

class PackWriter final : public TileSink {
 public:
  static Result<std::unique_ptr<PackWriter>> create(const std::string& path, PackLayout layout);
  // The same, its temporary in a private directory (OutputFile::create_shared)
  // for other processes of the build to open by name and write their tiles.
  static Result<std::unique_ptr<PackWriter>> create_shared(const std::string& path, PackLayout layout);
  ~PackWriter();
  PackWriter(const PackWriter&) = delete;
  PackWriter& operator=(const PackWriter&) = delete;

  const PackLayout& layout() const { return placement_.layout; }
  const TilePlacement& placement() const { return placement_; }
  // Expected payload size of a tile of `layer` at `level` (before page padding).
  std::size_t payload_bytes(int level, Layer layer) const { return placement_.payload_bytes(level, layer); }

  // Writes one tile; `bytes` must equal payload_bytes(level, layer).
  Status write_tile(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes) override;

  // The temporary file the tiles go to until finish(): other processes of a
  // build write their tiles there, at placement()'s offsets, and hand their
  // checksums to add_written_tile().
  const std::string& write_path() const { return out_.write_path(); }
  // Tile `index` (of placement().tiles) was written to write_path() by
  // another process, with this checksum of its stored bytes.
  Status add_written_tile(std::size_t index, std::uint32_t crc32c);

  // Every tile must have been written. Makes the pack durable and visible.
  Status finish(const std::string& metadata_json);

  std::uint64_t file_bytes() const { return file_bytes_; }

 private:
  PackWriter(OutputFile out, TilePlacement placement);
  static Result<std::unique_ptr<PackWriter>> create(const std::string& path, PackLayout layout, bool shared);
  Status fail(Status status);

  OutputFile out_;  // the temporary until finish() renames it
  std::string path_;
  TilePlacement placement_;  // its tiles' checksums filled in as they are written
  std::vector<std::uint8_t> written_;
  std::uint64_t file_bytes_ = 0;
  bool finished_ = false;
};

template <class WriteAt>
Result<TilePlacement::Stored> TilePlacement::store(int level, Layer layer, int tx, int ty, const void* payload,
                                                   std::size_t bytes, WriteAt&& write_at) const {
  const Result<std::size_t> index = find(level, layer, tx, ty, bytes);
  if (!index.ok()) return index.status();
  const TileEntry& entry = tiles[*index];
  std::uint32_t crc = crc32c(payload, bytes);
  const std::size_t pad = entry.bytes - bytes;
  if (pad > 0) {
    static const std::uint8_t zeros[kPageBytes] = {};
    crc = crc32c(zeros, pad, crc);
    VISVOL_RETURN_IF_ERROR(write_at(zeros, pad, entry.offset + bytes));
  }
  VISVOL_RETURN_IF_ERROR(write_at(payload, bytes, entry.offset));
  return Stored{*index, crc};
}

}  // namespace visvol::storage
