// Crafted packs for tests: the bytes of a valid pack with chosen fields
// rewritten and every checksum (tiles, tables, header) recomputed, so that
// only the contents are hostile, as an attacker who knows the format would
// make them.
#pragma once

#include <algorithm>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "storage/crc32c.hpp"
#include "storage/pack_format.hpp"

namespace visvol::storage::testing {

class CraftedPack {
 public:
  explicit CraftedPack(const std::string& valid_pack_path) {
    std::ifstream in(valid_pack_path, std::ios::binary | std::ios::ate);
    bytes_.resize(static_cast<std::size_t>(in.tellg()));
    in.seekg(0);
    in.read(bytes_.data(), static_cast<std::streamsize>(bytes_.size()));
  }

  PackHeader& header() { return *reinterpret_cast<PackHeader*>(bytes_.data()); }
  LevelEntry& level(int l) { return reinterpret_cast<LevelEntry*>(bytes_.data() + header().level_table_offset)[l]; }
  TileEntry& tile(int l, Layer layer, int tx, int ty) {
    const LevelEntry& e = level(l);
    const std::uint64_t n = e.first_tile + tile_index_in_level(layer, tx, ty, e.nx, e.ny);
    return reinterpret_cast<TileEntry*>(bytes_.data() + header().tile_table_offset)[n];
  }
  // Height post (i, j) of level l, in its tile.
  void set_height(int l, int i, int j, float h_m) {
    const TileEntry& t = tile(l, Layer::height, i / kTile2dPosts, j / kTile2dPosts);
    const std::size_t index = static_cast<std::size_t>((j % kTile2dPosts) * kTile2dPosts + i % kTile2dPosts);
    std::memcpy(bytes_.data() + t.offset + index * sizeof h_m, &h_m, sizeof h_m);
  }
  // Area factor of post (i, j) of level l, in its tile.
  void set_area(int l, int i, int j, float a) {
    const TileEntry& t = tile(l, Layer::area, i / kTile2dPosts, j / kTile2dPosts);
    const std::size_t index = static_cast<std::size_t>((j % kTile2dPosts) * kTile2dPosts + i % kTile2dPosts);
    std::memcpy(bytes_.data() + t.offset + index * sizeof a, &a, sizeof a);
  }
  // One float of a float32 visibility tile: voxel (i, j, k) of level l.
  void set_visibility(int l, int i, int j, int k, float f) {
    const TileEntry& t = tile(l, Layer::visibility, i / kBrickPosts, j / kBrickPosts);
    const std::size_t index =
        static_cast<std::size_t>((k * kBrickPosts + j % kBrickPosts) * kBrickPosts + i % kBrickPosts);
    std::memcpy(bytes_.data() + t.offset + index * sizeof f, &f, sizeof f);
  }
  // One component (0..2 displacement, 3 signed distance) of the terrain
  // force sample of band level b over post (i, j) of level l, in cm.
  void set_tff(int l, int i, int j, int b, int component, std::int16_t cm) {
    const TileEntry& t = tile(l, Layer::tff, i / kBrickPosts, j / kBrickPosts);
    const std::size_t index =
        ((static_cast<std::size_t>(b) * kBrickPosts + static_cast<std::size_t>(j % kBrickPosts)) * kBrickPosts +
         static_cast<std::size_t>(i % kBrickPosts)) *
            4 +
        static_cast<std::size_t>(component);
    std::memcpy(bytes_.data() + t.offset + index * sizeof cm, &cm, sizeof cm);
  }
  std::string metadata() {
    return std::string(bytes_.data() + header().metadata_offset, static_cast<std::size_t>(header().metadata_bytes));
  }
  // Replaces the metadata (it ends the file), resizing the file.
  void set_metadata(const std::string& json) {
    bytes_.resize(static_cast<std::size_t>(header().metadata_offset));
    bytes_.insert(bytes_.end(), json.begin(), json.end());
    header().metadata_bytes = json.size();
    header().file_bytes = bytes_.size();
  }

  // Recomputes every checksum and writes the file.
  void write(const std::string& path) {
    PackHeader& h = header();
    auto* tiles = reinterpret_cast<TileEntry*>(bytes_.data() + h.tile_table_offset);
    // (a crafted table may point anywhere: only entries inside the file)
    const std::uint64_t size = bytes_.size();
    const std::uint64_t entries =
        std::min<std::uint64_t>(h.tile_count, (size - h.tile_table_offset) / sizeof(TileEntry));
    for (std::uint64_t n = 0; n < entries; ++n) {
      if (tiles[n].offset > size || tiles[n].bytes > size - tiles[n].offset) continue;
      tiles[n].crc32c = crc32c(bytes_.data() + tiles[n].offset, tiles[n].bytes);
    }
    h.tables_crc32c = crc32c(bytes_.data() + h.level_table_offset, bytes_.size() - h.level_table_offset);
    h.header_crc32c = crc32c(&h, offsetof(PackHeader, header_crc32c));
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes_.data(), static_cast<std::streamsize>(bytes_.size()));
  }

 private:
  std::vector<char> bytes_;
};

}  // namespace visvol::storage::testing
