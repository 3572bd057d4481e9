// Reads a field pack by memory mapping it read-only.
//
// open() checks everything structural before anything is used: magic,
// version, header and table checksums, the file size against the header (a
// truncated pack is named as such), every level's grid and every tile entry's
// identity, offset, alignment and size. Tile checksums are checked by
// verify() and verify_level(), which name the bad tile. Nothing here trusts a
// number from the file without bounds.
//
// Thread-safety: a Pack is immutable after open(); concurrent reads are safe.
// Not real-time safe to open (I/O); the mapped bytes are read in place.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fields/terrain_force.hpp"
#include "fields/volume.hpp"
#include "rt/base/status.hpp"
#include "storage/pack_format.hpp"

namespace visvol::storage {

// What the metadata says, parsed.
struct PackMetadata {
  std::string json;          // the whole metadata object, as stored
  std::string crs_wkt;
  std::string crs_name;
  std::string tool;
  std::string source_path;
  std::string source_sha256;
};

class Pack {
 public:
  static Result<std::shared_ptr<const Pack>> open(const std::string& path);
  ~Pack();
  Pack(const Pack&) = delete;
  Pack& operator=(const Pack&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t file_bytes() const { return size_; }
  // The read-only mapping of the whole file (file_bytes() long).
  const std::uint8_t* mapping() const { return base_; }
  const PackHeader& header() const { return *header_; }
  const PackMetadata& metadata() const { return metadata_; }
  int level_count() const { return static_cast<int>(header_->level_count); }
  const LevelEntry& level(int l) const { return levels_[l]; }
  VisibilityEncoding encoding() const {
    return static_cast<VisibilityEncoding>(header_->visibility_encoding);
  }
  fields::TffParams tff_params() const {
    return {header_->band_offset_m, static_cast<int>(header_->band_levels)};
  }
  fields::VolumeGeometry geometry(int level) const;

  // The entry and bytes of a tile (entries are validated at open()).
  const TileEntry& tile(int level, Layer layer, int tx, int ty) const;
  const std::uint8_t* tile_data(const TileEntry& t) const { return base_ + t.offset; }
  std::uint64_t tile_count() const { return header_->tile_count; }
  const TileEntry& tile_entry(std::uint64_t n) const { return tiles_[n]; }

  // Checks one tile's checksum, naming it on failure.
  Status verify_tile(const TileEntry& t) const;
  // Checks the tiles of one level, or all tiles; progress gets fractions.
  Status verify_level(int level) const;
  Status verify(const std::function<void(double)>& progress = {}) const;

  // A short name for a tile in messages: "visibility tile (3, 2) of level 0".
  static std::string describe(const TileEntry& t);

 private:
  Pack() = default;
  Status validate_structure();
  Status parse_metadata();

  std::string path_;
  const std::uint8_t* base_ = nullptr;
  std::uint64_t size_ = 0;
  const PackHeader* header_ = nullptr;
  const LevelEntry* levels_ = nullptr;
  const TileEntry* tiles_ = nullptr;
  PackMetadata metadata_;
};

// One level of detail of a pack as the field sampler reads it: heights, F_p
// and the terrain force field band, through per-tile pointers resolved once.
// open() checks the level's tile checksums first, which reads the whole level;
// a console whose pack is larger than its memory passes TileCheck::deferred
// and has the tile pager check each tile as it makes it resident.
enum class TileCheck : std::uint8_t { at_open, deferred };

class PackLevel {
 public:
  static Result<PackLevel> open(std::shared_ptr<const Pack> pack, int level,
                                TileCheck check = TileCheck::at_open);

  const fields::VolumeGeometry& geometry() const { return geometry_; }
  // Inline: the sampler calls these tens of times per query.
  float post(int i, int j) const {
    return read_at<float>(height_[tile2d(i, j)], static_cast<std::size_t>((j % kTile2dPosts) * kTile2dPosts + i % kTile2dPosts));
  }
  float area(int i, int j) const {
    return read_at<float>(area_[tile2d(i, j)], static_cast<std::size_t>((j % kTile2dPosts) * kTile2dPosts + i % kTile2dPosts));
  }
  float voxel(int i, int j, int k) const {
    const std::uint8_t* t = visibility_[brick(i, j)];
    const std::size_t index =
        static_cast<std::size_t>((k * kBrickPosts + j % kBrickPosts) * kBrickPosts + i % kBrickPosts);
    return quantised_ ? dequantise_visibility(read_at<std::uint16_t>(t, index)) : read_at<float>(t, index);
  }
  fields::TffSample tff(int i, int j, int b) const {
    const std::uint8_t* t = tff_tiles_[brick(i, j)];
    const std::size_t index =
        static_cast<std::size_t>(((b * kBrickPosts + j % kBrickPosts) * kBrickPosts + i % kBrickPosts) * 4);
    fields::TffSample s;
    s.dx_m = static_cast<float>(read_at<std::int16_t>(t, index) * kTffUnitM);
    s.dy_m = static_cast<float>(read_at<std::int16_t>(t, index + 1) * kTffUnitM);
    s.dz_m = static_cast<float>(read_at<std::int16_t>(t, index + 2) * kTffUnitM);
    s.signed_distance_m = static_cast<float>(read_at<std::int16_t>(t, index + 3) * kTffUnitM);
    return s;
  }
  const fields::TffParams& tff_params() const { return tff_; }
  const Pack& pack() const { return *pack_; }
  std::shared_ptr<const Pack> shared_pack() const { return pack_; }
  int level() const { return level_; }

 private:
  template <typename T>
  static T read_at(const std::uint8_t* tile, std::size_t index) {
    T v;
    std::memcpy(&v, tile + index * sizeof(T), sizeof(T));
    return v;
  }
  std::size_t tile2d(int i, int j) const {
    return static_cast<std::size_t>((j / kTile2dPosts) * tiles2d_x_ + i / kTile2dPosts);
  }
  std::size_t brick(int i, int j) const {
    return static_cast<std::size_t>((j / kBrickPosts) * bricks_x_ + i / kBrickPosts);
  }

  std::shared_ptr<const Pack> pack_;
  int level_ = 0;
  fields::VolumeGeometry geometry_;
  fields::TffParams tff_;
  bool quantised_ = true;
  int tiles2d_x_ = 0, bricks_x_ = 0;
  std::vector<const std::uint8_t*> height_, area_, visibility_, tff_tiles_;
};

}  // namespace visvol::storage
