// What the readers rely on in a pack's contents, beyond its structure and
// checksums: a pack whose checksums are consistent but whose numbers are
// hostile (NaN heights, a denormal dz, metadata of the wrong types) is refused
// here, by Pack::open, before any reader indexes a grid with its numbers.
//
// Each check names the pack file, the level or tile and the problem. Pure
// functions of the mapped bytes; offline or at start-up (not real-time safe:
// they allocate their messages).
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "base/status.hpp"
#include "storage/pack_format.hpp"

namespace visvol::storage {

// Sane ranges of a level's geometry (metres). Wider than any terrain the
// builder makes; narrow enough that every grid index and every product of
// sizes a reader computes stays finite and within int.
inline constexpr double kMinSpacingM = 1e-3;  // post spacing
inline constexpr double kMaxSpacingM = 1e6;
inline constexpr double kMaxExtentM = 1e8;         // (posts - 1) x spacing, each side
inline constexpr double kMaxAbsCoordinateM = 1e9;  // origin x, y
inline constexpr double kMinDzM = 1e-3;            // voxel level spacing
inline constexpr double kMaxDzM = 1e5;
inline constexpr double kMaxAbsLevelHeightM = 2e5;  // z0 and the top level

// Every level's geometry: finite, within the ranges above, the top level above
// the lowest, and each coarser level the builder's 2:1 reduction of the one
// before (half the posts, twice the spacing, the same area and voxel levels).
// `levels` holds `count` entries whose grid sizes open() has bounded already.
Status check_level_geometry(const LevelEntry* levels, int count, const std::string& path);

// The height posts of one level's height tile (the padding beyond the grid
// excluded): finite, and within the level's voxel levels give or take one.
Status check_height_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                         const std::string& path);

// The area factors of one level's area tile (padding excluded): finite and
// at least 1 (sqrt(1 + slope^2)).
Status check_area_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                       const std::string& path);

// A float32 visibility tile: every F_p finite and in [0, 1] (uint16 tiles
// cannot hold anything else).
Status check_visibility_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                             const std::string& path);

// A terrain force field tile: every sample's displacement components and
// signed distance within the band's offset (a sample lies at most that far
// from its post's ground, so its nearest terrain point is no farther), in
// the tile's columns of the grid. (-327 m in a +-60 m band sent the
// console's rope wandering, exit 0.)
Status check_tff_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data, int band_levels,
                      double band_offset_m, const std::string& path);

// The metadata object's members that any reader uses, where present, of the
// type that reader expects ("tool" a string, "build" an object whose numbers
// are finite numbers, ...). Members it does not know are left alone.
Status check_metadata_types(const nlohmann::json& metadata, const std::string& path);

// The range the build parameters name (build.range_posts, 0 for
// range_shape "none") against the level table's: the two must agree, where
// the metadata names one. Errc::corrupt naming both.
Status check_metadata_range(const nlohmann::json& metadata, const LevelEntry& finest, const std::string& path);

}  // namespace visvol::storage
