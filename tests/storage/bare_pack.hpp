// Packs as the writer lays them out, with zero tiles and the metadata given:
// what an older build, or a forged one, leaves (planning bounds tests, the
// console's catalogue).
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "fields/field_params.hpp"
#include "storage/pack_writer.hpp"

namespace visvol::storage::testing {

// 40 x 30 posts of 30 m, post (0, 0) at (1000, 5000): posts span x 1000..2170, y 4130..5000.
inline fields::VolumeGeometry grid_40x30() {
  fields::VolumeGeometry g;
  g.nx = 40;
  g.ny = 30;
  g.nz = 4;
  g.spacing_m = 30;
  g.origin_x = 1000;
  g.origin_y = 5000;
  g.dz_m = 10;
  return g;
}

inline LevelEntry level_40x30(int range_posts) {
  const fields::VolumeGeometry g = grid_40x30();
  LevelEntry e{};
  e.nx = g.nx;
  e.ny = g.ny;
  e.nz = g.nz;
  e.range_posts = range_posts;
  e.spacing_m = g.spacing_m;
  e.origin_x = g.origin_x;
  e.origin_y = g.origin_y;
  e.dz_m = g.dz_m;
  return e;
}

// Writes the pack of `level0` at `path` (returned).
inline std::string write_bare_pack(const std::string& path, const LevelEntry& level0, const std::string& metadata) {
  PackLayout layout;
  layout.levels = {level0};
  layout.band_levels = 4;
  Result<std::unique_ptr<PackWriter>> w = PackWriter::create(path, layout);
  EXPECT_TRUE(w.ok()) << w.status().message();
  if (!w.ok()) return path;
  for (int l = 0; l < kLayerCount; ++l) {
    const Layer layer = static_cast<Layer>(l);
    const TileGrid g = tile_grid(layer, level0.nx, level0.ny);
    const std::vector<char> zeros((*w)->payload_bytes(0, layer), 0);
    for (int ty = 0; ty < g.tiles_y; ++ty)
      for (int tx = 0; tx < g.tiles_x; ++tx)
        EXPECT_TRUE((*w)->write_tile(0, layer, tx, ty, zeros.data(), zeros.size()).ok());
  }
  EXPECT_TRUE((*w)->finish(metadata).ok());
  return path;
}

}  // namespace visvol::storage::testing
