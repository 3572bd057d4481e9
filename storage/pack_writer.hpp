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

class PackWriter {
 public:
  static Result<std::unique_ptr<PackWriter>> create(const std::string& path, PackLayout layout);
  ~PackWriter();
  PackWriter(const PackWriter&) = delete;
  PackWriter& operator=(const PackWriter&) = delete;

  const PackLayout& layout() const { return layout_; }
  // Expected payload size of a tile of `layer` at `level` (before page padding).
  std::size_t payload_bytes(int level, Layer layer) const;

  // Writes one tile; `bytes` must equal payload_bytes(level, layer).
  Status write_tile(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes);

  // Every tile must have been written. Makes the pack durable and visible.
  Status finish(const std::string& metadata_json);

  std::uint64_t file_bytes() const { return file_bytes_; }

 private:
  PackWriter(OutputFile out, PackLayout layout);
  Status fail(Status status);

  OutputFile out_;  // the temporary until finish() renames it
  std::string path_;
  PackLayout layout_;
  std::vector<TileEntry> tiles_;
  std::vector<std::uint8_t> written_;
  std::uint64_t tables_offset_ = 0;  // end of the tiles
  std::uint64_t file_bytes_ = 0;
  bool finished_ = false;
};

}  // namespace visvol::storage
