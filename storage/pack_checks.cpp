#include "storage/pack_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fields/heightfield.hpp"
#include "io/json_text.hpp"

namespace visvol::storage {

namespace {

// "PATH: level L: " for messages.
std::string level_prefix(const std::string& path, int level) {
  return path + ": level " + std::to_string(level) + ": ";
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// v finite and in [lo, hi].
bool in_range(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// a and b equal within `tolerance`.
bool near(double a, double b, double tolerance) { return std::fabs(a - b) <= tolerance; }

// One level on its own: finite numbers in the sane ranges, grid extents that
// stay far from overflow, the top voxel level above the lowest.
Status check_one_level(const LevelEntry& e, const std::string& where) {
  if (!in_range(e.spacing_m, kMinSpacingM, kMaxSpacingM)) {
    return corrupt(where + "post spacing " + number(e.spacing_m) + " m is not a finite number in " +
                   number(kMinSpacingM) + ".." + number(kMaxSpacingM) + " m");
  }
  const double width_m = (e.nx - 1) * e.spacing_m, height_m = (e.ny - 1) * e.spacing_m;
  if (width_m > kMaxExtentM || height_m > kMaxExtentM) {
    return corrupt(where + "grid extent " + number(width_m) + " x " + number(height_m) + " m exceeds " +
                   number(kMaxExtentM) + " m");
  }
  if (!in_range(e.origin_x, -kMaxAbsCoordinateM, kMaxAbsCoordinateM) ||
      !in_range(e.origin_y, -kMaxAbsCoordinateM, kMaxAbsCoordinateM)) {
    return corrupt(where + "origin (" + number(e.origin_x) + ", " + number(e.origin_y) +
                   ") is not finite or beyond +-" + number(kMaxAbsCoordinateM) + " m");
  }
  if (!in_range(e.dz_m, kMinDzM, kMaxDzM)) {
    return corrupt(where + "voxel level spacing dz " + number(e.dz_m) + " m is not a finite number in " +
                   number(kMinDzM) + ".." + number(kMaxDzM) + " m");
  }
  const double top_m = e.z0_m + (e.nz - 1) * e.dz_m;
  if (!in_range(e.z0_m, -kMaxAbsLevelHeightM, kMaxAbsLevelHeightM) ||
      !in_range(top_m, -kMaxAbsLevelHeightM, kMaxAbsLevelHeightM) || !(top_m > e.z0_m)) {
    return corrupt(where + "voxel levels from " + number(e.z0_m) + " m to " + number(top_m) +
                   " m are not finite, not within +-" + number(kMaxAbsLevelHeightM) + " m or not rising");
  }
  if (e.range_posts < 0 || e.range_posts > fields::kMaxPostsPerSide) {
    return corrupt(where + "range of " + std::to_string(e.range_posts) + " posts is outside 0.." +
                   std::to_string(fields::kMaxPostsPerSide));
  }
  return Status::ok_status();
}

// A coarser level against the finer one before it: the builder's 2:1
// reduction (fields::downsample2), so that a lookup that falls back to the
// coarser level reads the same place and the same voxel heights.
Status check_reduction(const LevelEntry& fine, const LevelEntry& coarse, const std::string& where) {
  if (coarse.nx != fine.nx / 2 || coarse.ny != fine.ny / 2 || coarse.nz != fine.nz) {
    return corrupt(where + "grid " + std::to_string(coarse.nx) + " x " + std::to_string(coarse.ny) + " x " +
                   std::to_string(coarse.nz) + " is not half of the finer level's " + std::to_string(fine.nx) + " x " +
                   std::to_string(fine.ny) + " x " + std::to_string(fine.nz));
  }
  if (coarse.range_posts != fine.range_posts) {
    // the builder's range is in posts at every level (pack_build.cpp)
    return corrupt(where + "range of " + std::to_string(coarse.range_posts) + " posts differs from the finer level's " +
                   std::to_string(fine.range_posts));
  }
  const double tolerance_m = 1e-6 * fine.spacing_m;
  if (!near(coarse.spacing_m, 2 * fine.spacing_m, tolerance_m) ||
      !near(coarse.origin_x, fine.origin_x + 0.5 * fine.spacing_m, tolerance_m) ||
      !near(coarse.origin_y, fine.origin_y - 0.5 * fine.spacing_m, tolerance_m)) {
    return corrupt(where + "spacing " + number(coarse.spacing_m) + " m and origin (" + number(coarse.origin_x) + ", " +
                   number(coarse.origin_y) + ") do not cover the finer level's area (twice its spacing, " +
                   "origin half a post inside)");
  }
  const double dz_tolerance_m = 1e-9 * fine.dz_m;
  if (!near(coarse.z0_m, fine.z0_m, dz_tolerance_m) || !near(coarse.dz_m, fine.dz_m, dz_tolerance_m)) {
    return corrupt(where + "voxel levels (" + number(coarse.z0_m) + " m every " + number(coarse.dz_m) +
                   " m) differ from the finer level's (" + number(fine.z0_m) + " m every " + number(fine.dz_m) + " m)");
  }
  return Status::ok_status();
}

// The posts of a 2D tile that lie in the grid, as (x, y) within the tile.
template <typename Visit>
Status for_each_post(const LevelEntry& level, const TileEntry& tile, Visit visit) {
  const int x_end = std::min(kTile2dPosts, level.nx - tile.tx * kTile2dPosts);
  const int y_end = std::min(kTile2dPosts, level.ny - tile.ty * kTile2dPosts);
  for (int y = 0; y < y_end; ++y) {
    for (int x = 0; x < x_end; ++x) VISVOL_RETURN_IF_ERROR(visit(x, y));
  }
  return Status::ok_status();
}

}  // namespace

Status check_level_geometry(const LevelEntry* levels, int count, const std::string& path) {
  for (int l = 0; l < count; ++l) {
    const std::string where = level_prefix(path, l);
    VISVOL_RETURN_IF_ERROR(check_one_level(levels[l], where));
    if (l > 0) VISVOL_RETURN_IF_ERROR(check_reduction(levels[l - 1], levels[l], where));
  }
  return Status::ok_status();
}

Status check_height_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                         const std::string& path) {
  // one voxel level of slack: coarser levels average the finer posts
  const double lowest_m = level.z0_m - level.dz_m;
  const double highest_m = level.z0_m + level.nz * level.dz_m;
  return for_each_post(level, tile, [&](int x, int y) {
    float h;
    std::memcpy(&h, data + (static_cast<std::size_t>(y) * kTile2dPosts + static_cast<std::size_t>(x)) * sizeof h,
                sizeof h);
    if (std::isfinite(h) && h >= lowest_m && h <= highest_m) return Status::ok_status();
    const int i = tile.tx * kTile2dPosts + x, j = tile.ty * kTile2dPosts + y;
    return corrupt(path + ": height tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) + ") of level " +
                   std::to_string(tile.level) + ": post (" + std::to_string(i) + ", " + std::to_string(j) +
                   ") has height " + number(h) + " m, not a finite height within the " + "level's voxel levels (" +
                   number(level.z0_m) + ".." + number(level.z0_m + (level.nz - 1) * level.dz_m) + " m)");
  });
}

Status check_area_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                       const std::string& path) {
  // sqrt(1 + Tx^2 + Ty^2): 1 or more (in float too), and no more
  // than the steepest slope the level's heights allow (their whole span, one
  // level either side, between neighbouring posts, on both axes)
  const double steepest = (level.nz + 1) * level.dz_m / level.spacing_m;
  const double highest = std::sqrt(1.0 + 2.0 * steepest * steepest) * (1 + 1e-6);
  return for_each_post(level, tile, [&](int x, int y) {
    float a;
    std::memcpy(&a, data + (static_cast<std::size_t>(y) * kTile2dPosts + static_cast<std::size_t>(x)) * sizeof a,
                sizeof a);
    if (std::isfinite(a) && a >= 1.0f && a <= highest) return Status::ok_status();
    const int i = tile.tx * kTile2dPosts + x, j = tile.ty * kTile2dPosts + y;
    return corrupt(path + ": area tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) + ") of level " +
                   std::to_string(tile.level) + ": post (" + std::to_string(i) + ", " + std::to_string(j) +
                   ") has area factor " + number(a) + ", not a factor in 1.." + number(highest) +
                   " (the steepest slope the level's heights allow)");
  });
}

Status check_visibility_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data,
                             const std::string& path) {
  const int x_end = std::min(kBrickPosts, level.nx - tile.tx * kBrickPosts);
  const int y_end = std::min(kBrickPosts, level.ny - tile.ty * kBrickPosts);
  for (int k = 0; k < level.nz; ++k) {
    for (int y = 0; y < y_end; ++y) {
      for (int x = 0; x < x_end; ++x) {
        const std::size_t index =
            (static_cast<std::size_t>(k) * kBrickPosts + static_cast<std::size_t>(y)) * kBrickPosts +
            static_cast<std::size_t>(x);
        float f;
        std::memcpy(&f, data + index * sizeof f, sizeof f);
        if (f >= 0.0f && f <= 1.0f) continue;
        return corrupt(path + ": visibility tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) +
                       ") of level " + std::to_string(tile.level) + ": F_p at voxel (" +
                       std::to_string(tile.tx * kBrickPosts + x) + ", " + std::to_string(tile.ty * kBrickPosts + y) +
                       ", " + std::to_string(k) + ") is " + number(f) + ", not in [0, 1]");
      }
    }
  }
  return Status::ok_status();
}

namespace {
std::string centimetres(std::int16_t cm) {
  char text[16];
  std::snprintf(text, sizeof text, "%.2f", cm * kTffUnitM);
  return text;
}
}  // namespace

Status check_tff_tile(const LevelEntry& level, const TileEntry& tile, const std::uint8_t* data, int band_levels,
                      double band_offset_m, const std::string& path) {
  // centimetres: the offset, and its rounding
  const double most_cm = std::ceil(band_offset_m / kTffUnitM) + 1;
  const int x_end = std::min(kBrickPosts, level.nx - tile.tx * kBrickPosts);
  const int y_end = std::min(kBrickPosts, level.ny - tile.ty * kBrickPosts);
  static const char* const kNames[4] = {"x displacement", "y displacement", "z displacement", "signed distance"};
  for (int b = 0; b < band_levels; ++b) {
    for (int y = 0; y < y_end; ++y) {
      for (int x = 0; x < x_end; ++x) {
        const std::size_t index =
            ((static_cast<std::size_t>(b) * kBrickPosts + static_cast<std::size_t>(y)) * kBrickPosts +
             static_cast<std::size_t>(x)) *
            4;
        for (int c = 0; c < 4; ++c) {
          std::int16_t v;
          std::memcpy(&v, data + (index + static_cast<std::size_t>(c)) * sizeof v, sizeof v);
          if (std::abs(static_cast<double>(v)) <= most_cm) continue;
          return corrupt(path + ": terrain force tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) +
                         ") of level " + std::to_string(tile.level) + ": sample " + std::to_string(b) + " of column (" +
                         std::to_string(tile.tx * kBrickPosts + x) + ", " + std::to_string(tile.ty * kBrickPosts + y) +
                         ") has " + kNames[c] + " " + centimetres(v) + " m, beyond the band's +-" +
                         number(band_offset_m) + " m");
        }
      }
    }
  }
  return Status::ok_status();
}

namespace {

using Json = nlohmann::json;

// What a member must be, and a test for it.
struct Expect {
  const char* key;
  const char* what;  // "a string", for the message
  bool (*ok)(const Json&);
};

bool is_string(const Json& j) { return j.is_string(); }
bool is_object(const Json& j) { return j.is_object(); }
bool is_array(const Json& j) { return j.is_array(); }
bool is_boolean(const Json& j) { return j.is_boolean(); }
bool is_finite(const Json& j) { return j.is_number() && std::isfinite(j.get<double>()); }
bool is_count(const Json& j) { return j.is_number_integer() && j.get<std::int64_t>() >= 0; }
bool is_unit_number(const Json& j) { return is_finite(j) && j.get<double>() >= 0 && j.get<double>() <= 1; }
bool is_geotransform(const Json& j) {
  if (!j.is_array() || j.size() != 6) return false;
  for (const Json& v : j)
    if (!is_finite(v)) return false;
  return true;
}

// The writer's members (storage/pack_build.cpp) and what its readers
// (visvol info, plan, check, render, the console) take them to be.
constexpr Expect kTop[] = {
    {"format", "a string", is_string},        {"version", "a count", is_count},
    {"tool", "a string", is_string},          {"created_utc", "a string", is_string},
    {"crs_wkt", "a string", is_string},       {"crs_name", "a string", is_string},
    {"vertical_unit", "a string", is_string}, {"geotransform", "an array of 6 finite numbers", is_geotransform},
    {"source", "an object", is_object},       {"build", "an object", is_object},
    {"levels", "an array", is_array},
};
constexpr Expect kSource[] = {{"path", "a string", is_string}, {"sha256", "a string", is_string}};
constexpr Expect kBuild[] = {
    {"nz", "a count", is_count},
    {"ceiling_m", "a finite number", is_finite},
    {"eye_height_m", "a finite number", is_finite},
    {"range_shape", "a string", is_string},
    {"range_posts", "a count", is_count},
    {"curvature_coeff", "a number in 0..1", is_unit_number},
    {"exact_rings", "a count", is_count},
    {"weights", "true or false", is_boolean},
    {"levels_of_detail", "a count", is_count},
    {"visibility_encoding", "a string", is_string},
    {"tff_band_offset_m", "a finite number", is_finite},
    {"tff_band_levels", "a count", is_count},
};
constexpr Expect kLevel[] = {{"nx", "a count", is_count},
                             {"ny", "a count", is_count},
                             {"spacing_m", "a finite number", is_finite},
                             {"range_m", "a finite number", is_finite}};

template <std::size_t N>
Status check_members(const Json& object, const Expect (&expected)[N], const std::string& where) {
  for (const Expect& e : expected) {
    const auto it = object.find(e.key);
    if (it == object.end() || e.ok(*it)) continue;
    std::string value = json_text(*it);
    if (value.size() > 40) value = value.substr(0, 40) + "...";
    return corrupt(where + e.key + " is " + value + ", not " + e.what);
  }
  return Status::ok_status();
}

}  // namespace

Status check_metadata_types(const Json& metadata, const std::string& path) {
  const std::string where = path + ": metadata ";
  if (!metadata.is_object()) return corrupt(path + ": metadata is not a JSON object");
  VISVOL_RETURN_IF_ERROR(check_members(metadata, kTop, where));
  if (const auto s = metadata.find("source"); s != metadata.end()) {
    VISVOL_RETURN_IF_ERROR(check_members(*s, kSource, where + "source."));
  }
  if (const auto b = metadata.find("build"); b != metadata.end()) {
    VISVOL_RETURN_IF_ERROR(check_members(*b, kBuild, where + "build."));
  }
  if (const auto levels = metadata.find("levels"); levels != metadata.end()) {
    for (std::size_t n = 0; n < levels->size(); ++n) {
      const Json& level = (*levels)[n];
      const std::string name = where + "levels[" + std::to_string(n) + "]";
      if (!level.is_object()) return corrupt(name + " is not an object");
      VISVOL_RETURN_IF_ERROR(check_members(level, kLevel, name + "."));
    }
  }
  return Status::ok_status();
}

Status check_metadata_range(const Json& metadata, const LevelEntry& finest, const std::string& path) {
  const auto build = metadata.find("build");
  if (build == metadata.end() || !build->contains("range_posts")) return Status::ok_status();
  const auto shape = build->find("range_shape");
  const bool none = shape != build->end() && *shape == "none";
  // a count (check_metadata_types), and level ranges are 0.. (check_level_geometry)
  const std::uint64_t named = none ? 0 : (*build)["range_posts"].get<std::uint64_t>();
  if (named != static_cast<std::uint64_t>(finest.range_posts)) {
    return corrupt(path + ": metadata build.range_posts " + std::to_string(named) +
                   (none ? " (range_shape none)" : "") + " differs from level 0's range of " +
                   std::to_string(finest.range_posts) + " posts");
  }
  return Status::ok_status();
}

}  // namespace visvol::storage
