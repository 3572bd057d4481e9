#include "storage/pack_reader.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "io/input_file.hpp"
#include "io/json_input.hpp"
#include "storage/crc32c.hpp"
#include "storage/pack_checks.hpp"

namespace visvol::storage {

namespace {

bool within(std::uint64_t offset, std::uint64_t bytes, std::uint64_t size) {
  return offset <= size && bytes <= size - offset;
}

// ISA-L computes CRC32C with AVX-512 where the CPU has it and returns with
// the upper halves of the vector registers still in use. Until the next
// vzeroupper, every SSE instruction of the thread runs several times slower
// (6x measured on an AVX-512 EPYC), and threads it starts inherit the state:
// the real-time loop, started after its pack is opened and checked, for one.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx"))) void zero_upper_vector_state() { _mm256_zeroupper(); }
void clear_upper_vector_state() {
  static const bool has_avx = __builtin_cpu_supports("avx");
  if (has_avx) zero_upper_vector_state();
}
#else
void clear_upper_vector_state() {}
#endif

// crc32c(), leaving the vector registers clean.
std::uint32_t checksum(const void* data, std::size_t bytes) {
  const std::uint32_t crc = crc32c(data, bytes);
  clear_upper_vector_state();
  return crc;
}

// A finite number under `key` of `object`, or why there is none.
Result<double> finite_number(const nlohmann::json& object, const char* key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) return corrupt(where + key + " is missing");
  if (!it->is_number() || !std::isfinite(it->get<double>())) {
    std::string value = it->dump();
    if (value.size() > 40) value = value.substr(0, 40) + "...";
    return corrupt(where + key + " is " + value + ", not a finite number");
  }
  return it->get<double>();
}

// The planning bounds a pack records: five finite numbers, a box that is not
// empty and lies within level 0's posts, a margin >= 0.
Result<PlanningBounds> recorded_planning_bounds(const nlohmann::json& object, const fields::VolumeGeometry& finest,
                                                const std::string& where) {
  if (!object.is_object()) return corrupt(where + "is not a JSON object");
  double values[5];
  const char* keys[5] = {"xmin_m", "ymin_m", "xmax_m", "ymax_m", "margin_m"};
  for (int n = 0; n < 5; ++n) {
    Result<double> v = finite_number(object, keys[n], where);
    if (!v.ok()) return v.status();
    values[n] = *v;
  }
  PlanningBounds p;
  p.box = {values[0], values[1], values[2], values[3]};
  p.margin_m = values[4];
  p.recorded = true;
  if (p.margin_m < 0) return corrupt(where + "margin_m " + std::to_string(p.margin_m) + " is negative");
  if (p.box.empty()) return corrupt(where + describe(p.box) + " is empty");
  // The writer records exactly the rule's box; allow for nothing but rounding.
  const fields::Bounds2D grid = post_extent(finest);
  const double slack_m = 1e-6 * finest.spacing_m;
  if (p.box.xmin_m < grid.xmin_m - slack_m || p.box.xmax_m > grid.xmax_m + slack_m ||
      p.box.ymin_m < grid.ymin_m - slack_m || p.box.ymax_m > grid.ymax_m + slack_m) {
    return corrupt(where + describe(p.box) + " is outside level 0's posts, " + describe(grid));
  }
  return p;
}

// The planning bounds of a pack built before they were recorded: the rule on
// level 0 and the range shape its build parameters name (when they name none,
// the shape the level's range implies).
Result<PlanningBounds> derived_planning_bounds(const nlohmann::json& metadata, const LevelEntry& finest,
                                               const fields::VolumeGeometry& geometry, const std::string& where) {
  fields::RangeShape shape = finest.range_posts > 0 ? fields::RangeShape::cube : fields::RangeShape::none;
  const auto build = metadata.find("build");
  if (build != metadata.end() && build->is_object() && build->contains("range_shape")) {
    const nlohmann::json& name = (*build)["range_shape"];
    Result<fields::RangeShape> parsed = name.is_string()
                                            ? fields::parse_range_shape(name.get<std::string>())
                                            : Result<fields::RangeShape>(invalid_argument("is not a string"));
    if (!parsed.ok()) return corrupt(where + "build.range_shape: " + parsed.status().message());
    shape = *parsed;
  }
  if (shape != fields::RangeShape::none && finest.range_posts < 1) {
    return corrupt(where + "level 0 has a range of " + std::to_string(finest.range_posts) + " posts for a " +
                   fields::to_string(shape) + " range; cannot derive planning bounds");
  }
  return planning_bounds_rule(geometry, shape, finest.range_posts);
}

}  // namespace

fields::Bounds2D planning_bounds(const Pack& pack) { return pack.metadata().planning.box; }

Status check_planning_bounds(const Pack& pack) {
  if (!planning_bounds(pack).empty()) return Status::ok_status();
  return invalid_argument(pack.path() +
                          ": no planning bounds: the pack is no wider than twice its range, so F_p is short of "
                          "observers everywhere (build it from a larger DEM, see visvol build --area)");
}

Pack::~Pack() {
  if (base_) ::munmap(const_cast<std::uint8_t*>(base_), static_cast<std::size_t>(size_));
}

std::string Pack::describe(const TileEntry& t) {
  const char* layer = t.layer < kLayerCount ? to_string(static_cast<Layer>(t.layer)) : "unknown-layer";
  std::ostringstream s;
  s << layer << " tile (" << t.tx << ", " << t.ty << ") of level " << t.level;
  return s.str();
}

Result<InputFile> Pack::open_header(const std::string& path) {
  path_ = path;
  // never blocks on a FIFO; refuses what is not a regular file
  Result<InputFile> file = InputFile::open(path);
  if (!file.ok()) return file.status();
  size_ = file->size_bytes();
  if (size_ < sizeof(PackHeader)) {
    return corrupt(path + ": " + std::to_string(size_) +
                   " bytes, smaller than a pack header; not a visvol pack or truncated");
  }
  VISVOL_RETURN_IF_ERROR(file->read_at(&header_copy_, sizeof(PackHeader), 0));
  VISVOL_RETURN_IF_ERROR(validate_header());
  return file;
}

Result<std::shared_ptr<const Pack>> Pack::open(const std::string& path, PackAccess access) {
  std::shared_ptr<Pack> pack(new Pack());
  Result<InputFile> file = pack->open_header(path);
  if (!file.ok()) return file.status();
  VISVOL_RETURN_IF_ERROR(pack->read_tables(*file));
  VISVOL_RETURN_IF_ERROR(pack->validate_tiles());
  VISVOL_RETURN_IF_ERROR(pack->parse_metadata());
  if (access == PackAccess::mapped) {
    void* map = ::mmap(nullptr, static_cast<std::size_t>(pack->size_), PROT_READ, MAP_SHARED, file->fd(), 0);
    if (map == MAP_FAILED) return io_error(path + ": cannot map: " + std::strerror(errno));
    pack->base_ = static_cast<const std::uint8_t*>(map);
  }
  VISVOL_RETURN_IF_ERROR(pack->check_heights(*file));
  pack->file_.emplace(std::move(*file));
  return std::shared_ptr<const Pack>(std::move(pack));
}

Result<PackFootprint> Pack::footprint(const std::string& path) {
  Pack pack;
  Result<InputFile> file = pack.open_header(path);
  if (!file.ok()) return file.status();
  const PackHeader& h = *pack.header_;
  PackFootprint out;
  out.table_bytes = pack.size_ - h.level_table_offset;
  // (validate_header: 1..kMaxLodLevels levels, their table inside the file)
  for (std::uint32_t l = 0; l < h.level_count; ++l) {
    LevelEntry e;
    VISVOL_RETURN_IF_ERROR(file->read_at(&e, sizeof e, h.level_table_offset + l * sizeof(LevelEntry)));
    out.height_bytes += static_cast<std::uint64_t>(std::clamp(e.nx, 0, 1 << 20)) *
                        static_cast<std::uint64_t>(std::clamp(e.ny, 0, 1 << 20)) * sizeof(float);
  }
  return out;
}

Status Pack::validate_header() {
  const PackHeader& h = *header_;
  std::ostringstream msg;
  msg << path_ << ": ";
  auto bad = [&](const std::string& what) { return corrupt(msg.str() + what); };
  if (std::memcmp(h.magic, kPackMagic, sizeof h.magic) != 0) return bad("not a visvol pack (bad magic)");
  if (h.version != kPackVersion) {
    return Status(Errc::unsupported, msg.str() + "pack version " + std::to_string(h.version) +
                                         ", this build reads version " + std::to_string(kPackVersion));
  }
  if (checksum(&h, offsetof(PackHeader, header_crc32c)) != h.header_crc32c) {
    return bad("header checksum mismatch");
  }
  if (h.file_bytes != size_) {
    return bad(h.file_bytes > size_
                   ? "truncated: " + std::to_string(size_) + " bytes, the header says " + std::to_string(h.file_bytes)
                   : "file is " + std::to_string(size_) + " bytes, the header says " + std::to_string(h.file_bytes));
  }
  if (h.header_bytes != sizeof(PackHeader) || h.page_bytes != kPageBytes || h.level_entry_bytes != sizeof(LevelEntry) ||
      h.tile_entry_bytes != sizeof(TileEntry) || h.tile2d_posts != static_cast<std::uint32_t>(kTile2dPosts) ||
      h.brick_posts != static_cast<std::uint32_t>(kBrickPosts)) {
    return bad("header sizes (header, page, entry, tile) do not match this format");
  }
  // Zeros in version 1: a writer that gives them a meaning is another version.
  const auto reserved =
      std::find_if(std::begin(h.reserved), std::end(h.reserved), [](std::uint8_t v) { return v != 0; });
  if (reserved != std::end(h.reserved)) {
    const std::size_t at = offsetof(PackHeader, reserved) + static_cast<std::size_t>(reserved - std::begin(h.reserved));
    return bad("reserved header byte " + std::to_string(at) + " is " + std::to_string(*reserved) +
               ", not 0: written by another version of the format or damaged");
  }
  if (h.level_count < 1 || h.level_count > static_cast<std::uint32_t>(kMaxLodLevels)) {
    return bad("level_count " + std::to_string(h.level_count) + " is outside 1.." + std::to_string(kMaxLodLevels));
  }
  if (h.visibility_encoding > 1)
    return bad("visibility_encoding " + std::to_string(h.visibility_encoding) + " is unknown");
  if (h.band_levels < 2 || h.band_levels > static_cast<std::uint32_t>(kMaxBandLevels) ||
      !(h.band_offset_m >= kMinBandOffsetM && h.band_offset_m <= kMaxBandOffsetM)) {
    return bad("terrain force band (" + std::to_string(h.band_levels) + " levels, offset " +
               std::to_string(h.band_offset_m) + " m) is out of range");
  }
  const std::uint64_t level_bytes = std::uint64_t{h.level_count} * sizeof(LevelEntry);
  if (h.level_table_offset % 8 != 0 || h.level_table_offset < sizeof(PackHeader) ||
      !within(h.level_table_offset, level_bytes, size_)) {
    return bad("level table (offset " + std::to_string(h.level_table_offset) + ") is outside the file");
  }
  if (h.tile_count > size_ / sizeof(TileEntry) || h.tile_table_offset % 8 != 0 ||
      h.tile_table_offset != h.level_table_offset + level_bytes ||
      !within(h.tile_table_offset, h.tile_count * sizeof(TileEntry), size_)) {
    return bad("tile table (offset " + std::to_string(h.tile_table_offset) + ", " + std::to_string(h.tile_count) +
               " tiles) is outside the file");
  }
  if (h.metadata_offset != h.tile_table_offset + h.tile_count * sizeof(TileEntry) ||
      !within(h.metadata_offset, h.metadata_bytes, size_) || h.metadata_offset + h.metadata_bytes != size_) {
    return bad("metadata (offset " + std::to_string(h.metadata_offset) + ", " + std::to_string(h.metadata_bytes) +
               " bytes) is outside the file");
  }
  if (h.metadata_bytes > kMaxMetadataBytes) {
    return bad("metadata of " + std::to_string(h.metadata_bytes) + " bytes, more than the " +
               std::to_string(kMaxMetadataBytes) + " a pack may hold");
  }
  return Status::ok_status();
}

// The level table first: its grids say how many tiles there are, so the tile
// table read next is no larger than the levels need (a file claiming more is
// refused before anything that size is allocated).
Status Pack::read_tables(const InputFile& file) {
  const PackHeader& h = *header_;
  // A level table that does not hold together is more often damage than
  // forgery: the checksum, streamed over the tables in small reads (nothing
  // their claimed size allocated), says which.
  auto bad = [&](const std::string& what) {
    std::vector<std::uint8_t> chunk(std::size_t{1} << 16);
    std::uint32_t crc = 0;
    for (std::uint64_t at = h.level_table_offset; at < size_;) {
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), size_ - at));
      if (!file.read_at(chunk.data(), n, at).ok()) break;
      crc = crc32c(chunk.data(), n, crc);
      at += n;
    }
    clear_upper_vector_state();
    return corrupt(path_ + ": " + (crc != h.tables_crc32c ? "table or metadata checksum mismatch" : what));
  };
  const std::uint64_t level_bytes = std::uint64_t{h.level_count} * sizeof(LevelEntry);
  tables_.resize(static_cast<std::size_t>(level_bytes));
  VISVOL_RETURN_IF_ERROR(file.read_at(tables_.data(), tables_.size(), h.level_table_offset));
  std::uint64_t expected_first = 0;
  for (std::uint32_t l = 0; l < h.level_count; ++l) {
    LevelEntry e;
    std::memcpy(&e, tables_.data() + l * sizeof(LevelEntry), sizeof e);
    const std::string name = "level " + std::to_string(l) + ": ";
    if (e.nx < 2 || e.ny < 2 || e.nx > 32768 || e.ny > 32768 || e.nz < 2 || e.nz > kMaxVoxelLevels) {
      return bad(name + "grid " + std::to_string(e.nx) + " x " + std::to_string(e.ny) + " x " + std::to_string(e.nz) +
                 " is out of range");
    }
    if (e.first_tile != expected_first) {
      return bad(name + "first_tile " + std::to_string(e.first_tile) + ", expected " + std::to_string(expected_first));
    }
    expected_first += tiles_in_level(e.nx, e.ny);
  }
  if (expected_first != h.tile_count) {
    return bad("tile_count " + std::to_string(h.tile_count) + ", the levels need " + std::to_string(expected_first));
  }
  // the tile table and metadata, up to the end of the file (validate_header)
  tables_.resize(static_cast<std::size_t>(size_ - h.level_table_offset));
  VISVOL_RETURN_IF_ERROR(
      file.read_at(tables_.data() + level_bytes, tables_.size() - level_bytes, h.level_table_offset + level_bytes));
  if (checksum(tables_.data(), tables_.size()) != h.tables_crc32c) {
    return corrupt(path_ + ": table or metadata checksum mismatch");
  }
  // operator new's alignment suits both tables (their offsets are multiples of 8)
  levels_ = reinterpret_cast<const LevelEntry*>(tables_.data());
  tiles_ = reinterpret_cast<const TileEntry*>(tables_.data() + level_bytes);
  return Status::ok_status();
}

Status Pack::validate_tiles() {
  const PackHeader& h = *header_;
  auto bad = [&](const std::string& what) { return corrupt(path_ + ": " + what); };
  // the numbers readers index grids with: finite, sane, levels consistent
  VISVOL_RETURN_IF_ERROR(check_level_geometry(levels_, static_cast<int>(h.level_count), path_));
  // every tile entry: identity, alignment, size, inside the tile area, after
  // the one before it (as the writer lays them out): no two share bytes, so
  // the grids a pack declares are paid for in its size (a small file cannot
  // make its readers allocate for a huge grid)
  std::uint64_t n = 0;
  std::uint64_t end_of_previous = kPageBytes;
  for (std::uint32_t l = 0; l < h.level_count; ++l) {
    const LevelEntry& e = levels_[l];
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const TileGrid g = tile_grid(static_cast<Layer>(layer), e.nx, e.ny);
      const std::uint64_t bytes = round_up_to_page(
          tile_payload_bytes(static_cast<Layer>(layer), e.nz, encoding(), static_cast<int>(h.band_levels)));
      for (int ty = 0; ty < g.tiles_y; ++ty) {
        for (int tx = 0; tx < g.tiles_x; ++tx, ++n) {
          const TileEntry& t = tiles_[n];
          if (t.level != l || t.layer != layer || t.tx != tx || t.ty != ty) {
            return bad("tile entry " + std::to_string(n) + " is " + describe(t) + ", expected " +
                       to_string(static_cast<Layer>(layer)) + " tile (" + std::to_string(tx) + ", " +
                       std::to_string(ty) + ") of level " + std::to_string(l));
          }
          if (t.bytes != bytes || t.offset % kPageBytes != 0 || t.offset < kPageBytes ||
              !within(t.offset, t.bytes, h.level_table_offset)) {
            return bad(describe(t) + ": offset " + std::to_string(t.offset) + " or size " + std::to_string(t.bytes) +
                       " is invalid");
          }
          if (t.offset < end_of_previous) {
            return bad(describe(t) + ": offset " + std::to_string(t.offset) +
                       " overlaps the tile before it (ending at " + std::to_string(end_of_previous) + ")");
          }
          end_of_previous = t.offset + t.bytes;
        }
      }
    }
  }
  return Status::ok_status();
}

Status Pack::parse_metadata() {
  const char* text =
      reinterpret_cast<const char*>(tables_.data() + (header_->metadata_offset - header_->level_table_offset));
  metadata_.json.assign(text, static_cast<std::size_t>(header_->metadata_bytes));
  // nesting limited: readers print and copy it (catalogue, info)
  Result<nlohmann::json> parsed = parse_json_input(metadata_.json, path_ + ": metadata");
  if (!parsed.ok()) return corrupt(parsed.status().message());
  try {
    const nlohmann::json& j = *parsed;
    VISVOL_RETURN_IF_ERROR(check_metadata_types(j, path_));
    VISVOL_RETURN_IF_ERROR(check_metadata_range(j, levels_[0], path_));
    auto str = [&](const char* key) {
      return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
    };
    metadata_.crs_wkt = str("crs_wkt");
    metadata_.crs_name = str("crs_name");
    metadata_.tool = str("tool");
    if (j.contains("source") && j["source"].is_object()) {
      const nlohmann::json& s = j["source"];
      if (s.contains("path") && s["path"].is_string()) metadata_.source_path = s["path"];
      if (s.contains("sha256") && s["sha256"].is_string()) metadata_.source_sha256 = s["sha256"];
    }
    const auto recorded = j.find("planning_bounds");
    Result<PlanningBounds> planning =
        recorded != j.end() ? recorded_planning_bounds(*recorded, geometry(0), path_ + ": metadata planning_bounds: ")
                            : derived_planning_bounds(j, levels_[0], geometry(0), path_ + ": metadata: ");
    if (!planning.ok()) return planning.status();
    metadata_.planning = *planning;
  } catch (const nlohmann::json::exception& e) {
    return corrupt(path_ + ": metadata: " + e.what());
  }
  return Status::ok_status();
}

fields::VolumeGeometry Pack::geometry(int level) const {
  const LevelEntry& e = levels_[level];
  fields::VolumeGeometry g;
  g.nx = e.nx;
  g.ny = e.ny;
  g.nz = e.nz;
  g.spacing_m = e.spacing_m;
  g.origin_x = e.origin_x;
  g.origin_y = e.origin_y;
  g.z0_m = e.z0_m;
  g.dz_m = e.dz_m;
  return g;
}

const TileEntry& Pack::tile(int level, Layer layer, int tx, int ty) const {
  const LevelEntry& e = levels_[level];
  return tiles_[e.first_tile + tile_index_in_level(layer, tx, ty, e.nx, e.ny)];
}

Status Pack::verify_tile(const TileEntry& t) const {
  if (base_ == nullptr) {
    std::vector<std::uint8_t> copy(static_cast<std::size_t>(t.bytes));
    return read_tile(t, copy.data());
  }
  return verify_tile_bytes(t, base_ + t.offset);
}

Status Pack::read_tile(const TileEntry& t, std::uint8_t* out) const {
  const Status read = file_->read_at(out, static_cast<std::size_t>(t.bytes), t.offset);
  if (!read.ok()) return Status(read.code(), read.message() + " (" + describe(t) + ")");
  return verify_tile_bytes(t, out);
}

Status Pack::verify_tile_bytes(const TileEntry& t, const std::uint8_t* bytes) const {
  if (checksum(bytes, t.bytes) != t.crc32c) {
    return corrupt(path_ + ": " + describe(t) + ": checksum mismatch");
  }
  // float32 F_p is read where the checksum is: a value outside [0, 1] never reaches a reader
  if (t.layer == static_cast<std::uint16_t>(Layer::visibility) && encoding() == VisibilityEncoding::float32) {
    return check_visibility_tile(levels_[t.level], t, bytes, path_);
  }
  // heights were checked at open(); a copy read later is checked again (a
  // checksum is no proof against a file rewritten on purpose)
  if (t.layer == static_cast<std::uint16_t>(Layer::height)) return check_height_tile(levels_[t.level], t, bytes, path_);
  // area factors: only exported, and so checked where they are read
  if (t.layer == static_cast<std::uint16_t>(Layer::area)) return check_area_tile(levels_[t.level], t, bytes, path_);
  if (t.layer == static_cast<std::uint16_t>(Layer::tff)) {
    return check_tff_tile(levels_[t.level], t, bytes, static_cast<int>(header_->band_levels), header_->band_offset_m,
                          path_);
  }
  return Status::ok_status();
}

Status Pack::check_heights(const InputFile& file) const {
  std::vector<std::uint8_t> copy;  // an inspected pack's tile, as read
  for (int l = 0; l < level_count(); ++l) {
    const LevelEntry& e = levels_[l];
    const TileGrid g = tile_grid(Layer::height, e.nx, e.ny);
    for (int ty = 0; ty < g.tiles_y; ++ty) {
      for (int tx = 0; tx < g.tiles_x; ++tx) {
        const TileEntry& t = tile(l, Layer::height, tx, ty);
        const std::uint8_t* bytes = base_ ? tile_data(t) : nullptr;
        if (bytes == nullptr) {
          copy.resize(static_cast<std::size_t>(t.bytes));
          VISVOL_RETURN_IF_ERROR(file.read_at(copy.data(), copy.size(), t.offset));
          bytes = copy.data();
        }
        VISVOL_RETURN_IF_ERROR(check_height_tile(e, t, bytes, path_));
      }
    }
  }
  return Status::ok_status();
}

Status Pack::verify_level(int level) const {
  const LevelEntry& e = levels_[level];
  const std::uint64_t end = e.first_tile + tiles_in_level(e.nx, e.ny);
  for (std::uint64_t n = e.first_tile; n < end; ++n) VISVOL_RETURN_IF_ERROR(verify_tile(tiles_[n]));
  return Status::ok_status();
}

Status Pack::verify(const std::function<void(double)>& progress) const {
  const std::uint64_t count = header_->tile_count;
  for (std::uint64_t n = 0; n < count; ++n) {
    VISVOL_RETURN_IF_ERROR(verify_tile(tiles_[n]));
    if (progress && (n % 64 == 0 || n + 1 == count)) progress(double(n + 1) / double(count));
  }
  return Status::ok_status();
}

Result<PackLevel> PackLevel::open(std::shared_ptr<const Pack> pack, int level, TileCheck check) {
  if (pack->mapping() == nullptr) {
    return Status(Errc::state, pack->path() + ": opened for inspection, not mapped: its levels cannot be read");
  }
  if (level >= 0 && level < pack->level_count() && check == TileCheck::at_open) {
    VISVOL_RETURN_IF_ERROR(pack->verify_level(level));
  }
  Result<PackLevel> v = open_unset(std::move(pack), level);
  if (!v.ok()) return v;
  const Pack& p = *v->pack_;
  const LevelEntry& e = p.level(level);
  auto collect = [&](Layer layer, std::vector<const std::uint8_t*>& out) {
    const TileGrid g = tile_grid(layer, e.nx, e.ny);
    for (int ty = 0; ty < g.tiles_y; ++ty)
      for (int tx = 0; tx < g.tiles_x; ++tx)
        out[static_cast<std::size_t>(ty * g.tiles_x + tx)] = p.tile_data(p.tile(level, layer, tx, ty));
  };
  collect(Layer::height, v->height_);
  collect(Layer::area, v->area_);
  collect(Layer::visibility, v->visibility_);
  collect(Layer::tff, v->tff_tiles_);
  return v;
}

Result<PackLevel> PackLevel::open_unset(std::shared_ptr<const Pack> pack, int level) {
  if (level < 0 || level >= pack->level_count()) {
    return invalid_argument(pack->path() + ": no level of detail " + std::to_string(level) + " (it has " +
                            std::to_string(pack->level_count()) + ")");
  }
  PackLevel v;
  v.pack_ = pack;
  v.level_ = level;
  v.geometry_ = pack->geometry(level);
  v.tff_ = pack->tff_params();
  v.quantised_ = pack->encoding() == VisibilityEncoding::uint16;
  const LevelEntry& e = pack->level(level);
  auto unset = [&](Layer layer, std::vector<const std::uint8_t*>& out, int& tiles_x) {
    const TileGrid g = tile_grid(layer, e.nx, e.ny);
    tiles_x = g.tiles_x;
    out.assign(static_cast<std::size_t>(g.count()), nullptr);
  };
  int unused = 0;
  unset(Layer::height, v.height_, v.tiles2d_x_);
  unset(Layer::area, v.area_, unused);
  unset(Layer::visibility, v.visibility_, v.bricks_x_);
  unset(Layer::tff, v.tff_tiles_, unused);
  return v;
}

}  // namespace visvol::storage
