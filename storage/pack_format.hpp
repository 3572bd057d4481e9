// The field pack: one file per terrain, laid out for memory mapping.
//
// This header is the contract between the writer (offline) and the reader
// (the console); both include it and nothing else describes the format.
//
//   offset 0            PackHeader (one page)
//   page-aligned        tiles: every layer of every level of detail
//   after the tiles     level table, tile table, metadata (JSON, UTF-8)
//
// All numbers are little-endian. Every tile starts on a page boundary and has
// its own CRC32C; the header has one, and one more covers the tables and the
// metadata, so any torn or corrupted byte is found and named.
//
// Layers of a level (tile shapes in posts):
//   height      float32 m, 2D, 64 x 64 posts per tile
//   area        float32 area factor A, 2D, 64 x 64
//   visibility  F_p, 16 x 16 columns x nz levels, uint16 (F * 65535) or float32;
//               within a tile: index ((k * 16) + y) * 16 + x
//   tff         terrain force field band, 16 x 16 columns x band levels, 4 x int16
//               per sample: outward displacement from the nearest point of the
//               triangulated terrain (x, y, z) and the signed distance (negative
//               inside the terrain), all in centimetres; within a tile: index
//               (((b * 16) + y) * 16 + x) * 4 + component
// Tiles on the grid's east and south edges are padded to full size with zeros.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace visvol::storage {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the pack format is little-endian");

inline constexpr char kPackMagic[8] = {'V', 'I', 'S', 'V', 'O', 'L', 'P', 'K'};
inline constexpr std::uint32_t kPackVersion = 1;
inline constexpr std::uint32_t kPageBytes = 4096;
inline constexpr int kTile2dPosts = 64;   // height and area tiles
inline constexpr int kBrickPosts = 16;    // visibility and tff tiles (columns a side)
inline constexpr int kMaxLodLevels = 16;  // levels of detail
inline constexpr int kMaxVoxelLevels = 255;
inline constexpr int kMaxBandLevels = 64;
// The metadata JSON (a few kilobytes: CRS, source, build parameters): a
// reader refuses more before reading it.
inline constexpr std::uint64_t kMaxMetadataBytes = std::uint64_t{16} << 20;

enum class Layer : std::uint16_t { height = 0, area = 1, visibility = 2, tff = 3 };
inline constexpr int kLayerCount = 4;
const char* to_string(Layer layer);

enum class VisibilityEncoding : std::uint32_t { float32 = 0, uint16 = 1 };

struct PackHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t header_bytes;  // sizeof(PackHeader)
  std::uint64_t file_bytes;    // size of the whole file
  std::uint32_t page_bytes;    // kPageBytes
  std::uint32_t level_count;   // levels of detail, 1..kMaxLodLevels
  std::uint64_t level_table_offset;
  std::uint32_t level_entry_bytes;  // sizeof(LevelEntry)
  std::uint32_t tile_entry_bytes;   // sizeof(TileEntry)
  std::uint64_t tile_table_offset;
  std::uint64_t tile_count;
  std::uint64_t metadata_offset;
  std::uint64_t metadata_bytes;
  std::uint32_t tile2d_posts;         // kTile2dPosts
  std::uint32_t brick_posts;          // kBrickPosts
  std::uint32_t visibility_encoding;  // VisibilityEncoding
  std::uint32_t band_levels;          // tff samples per column, 2..kMaxBandLevels
  double band_offset_m;               // tff band: from terrain - offset to terrain + offset
  std::uint32_t tables_crc32c;        // level table + tile table + metadata, in file order
  std::uint8_t reserved[3984];        // zeros
  std::uint32_t header_crc32c;        // every byte before this field
};
static_assert(sizeof(PackHeader) == kPageBytes, "the header is one page");
static_assert(std::is_trivially_copyable_v<PackHeader>);
static_assert(offsetof(PackHeader, level_table_offset) == 32);
static_assert(offsetof(PackHeader, band_offset_m) == 96);
static_assert(offsetof(PackHeader, header_crc32c) == kPageBytes - 4);

struct LevelEntry {
  std::int32_t nx, ny, nz;    // posts a side, voxel levels
  std::int32_t range_posts;   // the field's range at this level
  double spacing_m;           // post spacing
  double origin_x, origin_y;  // world coordinates of post (0, 0), the north-west post
  double z0_m, dz_m;          // voxel level heights: z0 + k * dz
  std::uint64_t first_tile;   // index of this level's first tile entry
};
static_assert(sizeof(LevelEntry) == 64);
static_assert(offsetof(LevelEntry, spacing_m) == 16);
static_assert(offsetof(LevelEntry, first_tile) == 56);
static_assert(std::is_trivially_copyable_v<LevelEntry>);

struct TileEntry {
  std::uint64_t offset;                // page-aligned file offset
  std::uint32_t bytes;                 // tile size (a multiple of kPageBytes)
  std::uint32_t crc32c;                // of the tile's bytes
  std::uint16_t level, layer, tx, ty;  // which tile this is
};
static_assert(sizeof(TileEntry) == 24);
static_assert(offsetof(TileEntry, crc32c) == 12);
static_assert(std::is_trivially_copyable_v<TileEntry>);

// Tile grid of one layer of a level.
struct TileGrid {
  int edge = 0;  // posts a side per tile
  int tiles_x = 0, tiles_y = 0;
  int count() const { return tiles_x * tiles_y; }
};

inline int tile_edge(Layer layer) {
  return layer == Layer::height || layer == Layer::area ? kTile2dPosts : kBrickPosts;
}
inline TileGrid tile_grid(Layer layer, int nx, int ny) {
  const int e = tile_edge(layer);
  return {e, (nx + e - 1) / e, (ny + e - 1) / e};
}

// Bytes of one tile before page padding.
inline std::size_t tile_payload_bytes(Layer layer, int nz, VisibilityEncoding enc, int band_levels) {
  const std::size_t e = static_cast<std::size_t>(tile_edge(layer));
  switch (layer) {
    case Layer::height:
    case Layer::area: return e * e * sizeof(float);
    case Layer::visibility:
      return e * e * static_cast<std::size_t>(nz) *
             (enc == VisibilityEncoding::uint16 ? sizeof(std::uint16_t) : sizeof(float));
    case Layer::tff: return e * e * static_cast<std::size_t>(band_levels) * 4 * sizeof(std::int16_t);
  }
  return 0;
}
inline std::size_t round_up_to_page(std::size_t n) { return (n + kPageBytes - 1) / kPageBytes * kPageBytes; }

// Tile entries are ordered level, layer, ty, tx; this is the index within a
// level's entries.
inline std::uint64_t tile_index_in_level(Layer layer, int tx, int ty, int nx, int ny) {
  std::uint64_t index = 0;
  for (int l = 0; l < static_cast<int>(layer); ++l) {
    index += static_cast<std::uint64_t>(tile_grid(static_cast<Layer>(l), nx, ny).count());
  }
  const TileGrid g = tile_grid(layer, nx, ny);
  return index + static_cast<std::uint64_t>(ty) * static_cast<std::uint64_t>(g.tiles_x) +
         static_cast<std::uint64_t>(tx);
}
inline std::uint64_t tiles_in_level(int nx, int ny) {
  std::uint64_t n = 0;
  for (int l = 0; l < kLayerCount; ++l) {
    n += static_cast<std::uint64_t>(tile_grid(static_cast<Layer>(l), nx, ny).count());
  }
  return n;
}

// Visibility quantisation: F in [0, 1] to uint16 and back.
inline std::uint16_t quantise_visibility(float f) {
  const float c = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
  return static_cast<std::uint16_t>(c * 65535.0f + 0.5f);
}
inline float dequantise_visibility(std::uint16_t q) { return static_cast<float>(q) * (1.0f / 65535.0f); }

// Terrain force field samples are centimetres in int16: at most +-327 m.
inline constexpr double kTffUnitM = 0.01;
inline constexpr double kMaxBandOffsetM = 300.0;
inline constexpr double kMinBandOffsetM = 1.0;  // the build's least (fields/terrain_force.hpp)

}  // namespace visvol::storage
