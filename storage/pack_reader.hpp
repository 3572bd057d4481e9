// Reads a field pack: the header, tables and metadata are read (pread) into
// memory the Pack owns; the tiles are memory mapped read-only.
//
// open() checks everything structural before anything is used: magic,
// version, header and table checksums, the file size against the header (a
// truncated pack is named as such), every level's grid and every tile entry's
// identity, offset, alignment and size; and the contents readers index grids
// with (storage/pack_checks.hpp): every level's geometry finite, in sane
// ranges and consistent with the other levels, every height post finite and
// within its level's voxel levels, the metadata members of the types readers
// expect. Tile checksums (and float32 F_p in [0, 1]) are checked by verify()
// and verify_level(), which name the bad tile. Nothing here trusts a number
// from the file without bounds.
//
// A pack opened with PackAccess::inspect is not mapped at all: its height
// tiles are checked as read with pread, and so are its tiles when verified.
// A file truncated while a mapping of it is read raises SIGBUS, and one
// rewritten in place changes under the reader: whatever reads a pack that
// operators may replace reads copies (read_tile: pread, then the checksum),
// as the console's terrain catalogue, tile pager (storage/resident_pack.hpp)
// and path fitter (storage/cached_level.hpp) do. The Pack keeps the file
// open for that: a pack renamed over later is not the file read.
//
// Thread-safety: a Pack is immutable after open(); concurrent reads are safe.
// Not real-time safe to open (I/O); the mapped bytes are read in place.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"
#include "io/input_file.hpp"
#include "storage/pack_format.hpp"
#include "storage/planning_bounds.hpp"

namespace visvol::storage {

// What the metadata says, parsed.
struct PackMetadata {
  std::string json;  // the whole metadata object, as stored
  std::string crs_wkt;
  std::string crs_name;
  std::string tool;
  std::string source_path;
  std::string source_sha256;
  // The trusted region: "planning_bounds" as recorded, or for a pack built
  // before they were recorded, derived by the rule of planning_bounds.hpp from
  // level 0 and the range shape of "build" (then empty for a grid no wider
  // than twice its margin). Malformed values fail open().
  PlanningBounds planning;
};

enum class PackAccess : std::uint8_t { mapped, inspect };

// What opening a pack holds before any tile is read: its tables (levels,
// tiles, metadata), and what a console session on it holds at least: the
// heights of every level (storage::ResidentPack keeps them resident).
struct PackFootprint {
  std::uint64_t table_bytes = 0;
  std::uint64_t height_bytes = 0;
};

class Pack {
 public:
  static Result<std::shared_ptr<const Pack>> open(const std::string& path, PackAccess access = PackAccess::mapped);
  // From the header (its checksum checked) and the level table alone (not
  // yet checked: read to refuse a pack too large before its tables are, never
  // to trust one). Reads a page and the level table.
  static Result<PackFootprint> footprint(const std::string& path);
  ~Pack();
  Pack(const Pack&) = delete;
  Pack& operator=(const Pack&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t file_bytes() const { return size_; }
  // The read-only mapping of the whole file (file_bytes() long); null when
  // opened with PackAccess::inspect.
  const std::uint8_t* mapping() const { return base_; }
  const PackHeader& header() const { return *header_; }
  const PackMetadata& metadata() const { return metadata_; }
  int level_count() const { return static_cast<int>(header_->level_count); }
  const LevelEntry& level(int l) const { return levels_[l]; }
  VisibilityEncoding encoding() const { return static_cast<VisibilityEncoding>(header_->visibility_encoding); }
  fields::TffParams tff_params() const { return {header_->band_offset_m, static_cast<int>(header_->band_levels)}; }
  fields::VolumeGeometry geometry(int level) const;

  // The entry and bytes of a tile (entries are validated at open()); the
  // bytes only of a mapped pack (null for an inspected one).
  const TileEntry& tile(int level, Layer layer, int tx, int ty) const;
  const std::uint8_t* tile_data(const TileEntry& t) const { return base_ ? base_ + t.offset : nullptr; }
  std::uint64_t tile_count() const { return header_->tile_count; }
  const TileEntry& tile_entry(std::uint64_t n) const { return tiles_[n]; }

  // Checks one tile's checksum, naming it on failure: through the mapping,
  // or for an inspected pack on a copy read with pread.
  Status verify_tile(const TileEntry& t) const;
  // The same checks on a copy of the tile's t.bytes bytes (read with pread,
  // for instance, where a file changed under a mapping would raise SIGBUS);
  // a height tile's posts are checked again too (finite, within the levels).
  Status verify_tile_bytes(const TileEntry& t, const std::uint8_t* bytes) const;
  // Reads tile `t`'s t.bytes bytes into `out` with pread from the file
  // opened, and checks them (verify_tile_bytes): Errc::io naming the pack
  // when the file has been cut short since, Errc::corrupt when it changed.
  // Never touches the mapping. Any thread.
  Status read_tile(const TileEntry& t, std::uint8_t* out) const;
  // Checks the tiles of one level, or all tiles; progress gets fractions.
  Status verify_level(int level) const;
  Status verify(const std::function<void(double)>& progress = {}) const;

  // A short name for a tile in messages: "visibility tile (3, 2) of level 0".
  static std::string describe(const TileEntry& t);

 private:
  Pack() = default;
  // The header's own checks, then the level table (read first: it bounds the
  // tile table), then the tables and metadata read whole and checked.
  // Opens `path` for this pack, reads its header and validates it: the first
  // steps of open() and footprint().
  Result<InputFile> open_header(const std::string& path);
  Status validate_header();
  Status read_tables(const InputFile& file);
  Status validate_tiles();
  Status parse_metadata();
  // Every level's height posts finite and within its voxel levels (a scan of
  // the height layer, a small part of the pack; see pack_checks.hpp): through
  // the mapping, or read from `file` when there is none.
  Status check_heights(const InputFile& file) const;

  std::string path_;
  std::optional<InputFile> file_;       // open for read_tile (pread is safe from any thread)
  const std::uint8_t* base_ = nullptr;  // the mapping; null when inspected
  std::uint64_t size_ = 0;
  PackHeader header_copy_{};
  std::vector<std::uint8_t> tables_;  // level table .. end of file
  const PackHeader* header_ = &header_copy_;
  const LevelEntry* levels_ = nullptr;
  const TileEntry* tiles_ = nullptr;
  PackMetadata metadata_;
};

// The pack's planning bounds (world metres in its CRS): paths are trusted
// inside them. Recorded or derived; see PackMetadata::planning for which, and
// for the margin. Check empty() on packs built before they were recorded.
fields::Bounds2D planning_bounds(const Pack& pack);
// Errc::invalid_argument naming the pack where its planning bounds are empty
// (a pack built before they were recorded, no wider than twice its range):
// nothing in it can be planned, checked or flown.
Status check_planning_bounds(const Pack& pack);

// One level of detail of a pack as the field sampler reads it: heights, F_p
// and the terrain force field band, through per-tile pointers resolved once.
// open() checks the level's tile checksums first, which reads the whole level;
// a console whose pack is larger than its memory passes TileCheck::deferred
// and has the tile pager check each tile as it makes it resident.
enum class TileCheck : std::uint8_t { at_open, deferred };

class PackLevel {
 public:
  static Result<PackLevel> open(std::shared_ptr<const Pack> pack, int level, TileCheck check = TileCheck::at_open);

  const fields::VolumeGeometry& geometry() const { return geometry_; }
  // Inline: the sampler calls these tens of times per query.
  float post(int i, int j) const { return read_at<float>(height_[tile2d(i, j)], in_tile2d(i, j)); }
  float area(int i, int j) const { return read_at<float>(area_[tile2d(i, j)], in_tile2d(i, j)); }
  float voxel(int i, int j, int k) const {
    const std::uint8_t* t = visibility_[brick(i, j)];
    const std::size_t index = grid(k) * kBrickColumnStride + in_brick(i, j);
    return quantised_ ? dequantise_visibility(read_at<std::uint16_t>(t, index)) : read_at<float>(t, index);
  }
  fields::TffSample tff(int i, int j, int b) const {
    const std::uint8_t* t = tff_tiles_[brick(i, j)];
    const std::size_t index = (grid(b) * kBrickColumnStride + in_brick(i, j)) * 4;
    fields::TffSample s;
    s.dx_m = static_cast<float>(read_at<std::int16_t>(t, index) * kTffUnitM);
    s.dy_m = static_cast<float>(read_at<std::int16_t>(t, index + 1) * kTffUnitM);
    s.dz_m = static_cast<float>(read_at<std::int16_t>(t, index + 2) * kTffUnitM);
    s.signed_distance_m = static_cast<float>(read_at<std::int16_t>(t, index + 3) * kTffUnitM);
    return s;
  }
  const fields::TffParams& tff_params() const { return tff_; }

  // One column's bricks, found once: the sampler reads many levels of a
  // column per query (fields/sampler.hpp). Values are exactly voxel() and tff().
  class Column {
   public:
    float voxel(int k) const {
      const std::size_t index = grid(k) * kBrickColumnStride;
      return quantised_ ? dequantise_visibility(read_at<std::uint16_t>(visibility_, index))
                        : read_at<float>(visibility_, index);
    }
    fields::TffSample tff(int b) const {
      const std::size_t index = grid(b) * kBrickColumnStride * 4;
      fields::TffSample s;
      s.dx_m = static_cast<float>(read_at<std::int16_t>(tff_, index) * kTffUnitM);
      s.dy_m = static_cast<float>(read_at<std::int16_t>(tff_, index + 1) * kTffUnitM);
      s.dz_m = static_cast<float>(read_at<std::int16_t>(tff_, index + 2) * kTffUnitM);
      s.signed_distance_m = static_cast<float>(read_at<std::int16_t>(tff_, index + 3) * kTffUnitM);
      return s;
    }

   private:
    friend class PackLevel;
    // unset until column() fills them (a sampler's query holds sixteen)
    const std::uint8_t* visibility_;  // the column's voxel at level 0
    const std::uint8_t* tff_;         // its band sample 0
    bool quantised_;
  };
  Column column(int i, int j) const {
    const std::size_t b = brick(i, j), n = in_brick(i, j);
    Column c;
    c.quantised_ = quantised_;
    c.visibility_ = visibility_[b] + n * (quantised_ ? sizeof(std::uint16_t) : sizeof(float));
    c.tff_ = tff_tiles_[b] + n * 4 * sizeof(std::int16_t);
    return c;
  }

  const Pack& pack() const { return *pack_; }
  std::shared_ptr<const Pack> shared_pack() const { return pack_; }
  int level() const { return level_; }

 private:
  // Readers that hold copies of the tiles (read_tile) point the level at
  // them as they read them (storage/tile_copy.hpp): the level with every tile
  // pointer null, of a mapped or an inspected pack alike.
  friend class LevelCopies;
  static Result<PackLevel> open_unset(std::shared_ptr<const Pack> pack, int level);

  // Values between one level of a brick column and the next.
  static constexpr std::size_t kBrickColumnStride = std::size_t{kBrickPosts} * kBrickPosts;

  template <typename T>
  static T read_at(const std::uint8_t* tile, std::size_t index) {
    T v;
    std::memcpy(&v, tile + index * sizeof(T), sizeof(T));
    return v;
  }
  // Grid indices of a valid read are never negative: as unsigned, the tile
  // divisions and remainders below are plain shifts and masks.
  static std::size_t grid(int v) { return static_cast<std::size_t>(static_cast<unsigned>(v)); }
  std::size_t tile2d(int i, int j) const { return grid(j) / kTile2dPosts * grid(tiles2d_x_) + grid(i) / kTile2dPosts; }
  static std::size_t in_tile2d(int i, int j) { return grid(j) % kTile2dPosts * kTile2dPosts + grid(i) % kTile2dPosts; }
  std::size_t brick(int i, int j) const { return grid(j) / kBrickPosts * grid(bricks_x_) + grid(i) / kBrickPosts; }
  static std::size_t in_brick(int i, int j) { return grid(j) % kBrickPosts * kBrickPosts + grid(i) % kBrickPosts; }

  std::shared_ptr<const Pack> pack_;
  int level_ = 0;
  fields::VolumeGeometry geometry_;
  fields::TffParams tff_;
  bool quantised_ = true;
  int tiles2d_x_ = 0, bricks_x_ = 0;
  std::vector<const std::uint8_t*> height_, area_, visibility_, tff_tiles_;
};

}  // namespace visvol::storage
