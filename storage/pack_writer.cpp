#include "storage/pack_writer.hpp"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>

#include "io/atomic_file.hpp"
#include "storage/crc32c.hpp"
#include "storage/pack_checks.hpp"

namespace visvol::storage {

const char* to_string(Layer layer) {
  switch (layer) {
    case Layer::height: return "height";
    case Layer::area: return "area";
    case Layer::visibility: return "visibility";
    case Layer::tff: return "tff";
  }
  return "unknown";
}

Status validate(const PackLayout& layout) {
  std::ostringstream msg;
  if (layout.levels.empty() || layout.levels.size() > static_cast<std::size_t>(kMaxLodLevels)) {
    msg << "pack: " << layout.levels.size() << " levels of detail, 1.." << kMaxLodLevels << " allowed";
    return invalid_argument(msg.str());
  }
  if (layout.band_levels < 2 || layout.band_levels > kMaxBandLevels ||
      !(layout.band_offset_m >= kMinBandOffsetM && layout.band_offset_m <= kMaxBandOffsetM)) {
    msg << "pack: terrain force band of " << layout.band_levels << " levels over +-" << layout.band_offset_m
        << " m is outside 2.." << kMaxBandLevels << " levels, " << kMinBandOffsetM << ".." << kMaxBandOffsetM << " m";
    return invalid_argument(msg.str());
  }
  for (std::size_t l = 0; l < layout.levels.size(); ++l) {
    const LevelEntry& e = layout.levels[l];
    if (e.nx < 2 || e.ny < 2 || e.nx > 32768 || e.ny > 32768 || e.nz < 2 || e.nz > kMaxVoxelLevels ||
        !(e.spacing_m > 0) || !std::isfinite(e.spacing_m) || !(e.dz_m > 0) || !std::isfinite(e.dz_m) ||
        !std::isfinite(e.z0_m) || !std::isfinite(e.origin_x) || !std::isfinite(e.origin_y)) {
      msg << "pack: level " << l << " has an invalid grid (" << e.nx << " x " << e.ny << " x " << e.nz << ", spacing "
          << e.spacing_m << " m, dz " << e.dz_m << " m)";
      return invalid_argument(msg.str());
    }
  }
  // what the reader would refuse (pack_checks.hpp) is refused before anything is written
  const Status readable = check_level_geometry(layout.levels.data(), static_cast<int>(layout.levels.size()), "pack");
  if (!readable.ok()) return invalid_argument(readable.message());
  return Status::ok_status();
}

std::size_t payload_bytes(const PackLayout& layout, int level, Layer layer) {
  return tile_payload_bytes(layer, layout.levels[static_cast<std::size_t>(level)].nz, layout.encoding,
                            layout.band_levels);
}

Result<std::size_t> TilePlacement::find(int level, Layer layer, int tx, int ty, std::size_t bytes) const {
  if (level < 0 || level >= static_cast<int>(layout.levels.size())) {
    return invalid_argument("no level " + std::to_string(level));
  }
  const LevelEntry& e = layout.levels[static_cast<std::size_t>(level)];
  const TileGrid g = tile_grid(layer, e.nx, e.ny);
  if (tx < 0 || ty < 0 || tx >= g.tiles_x || ty >= g.tiles_y) {
    return invalid_argument("no " + std::string(to_string(layer)) + " tile (" + std::to_string(tx) + ", " +
                            std::to_string(ty) + ") at level " + std::to_string(level));
  }
  if (bytes != payload_bytes(level, layer)) {
    return invalid_argument(std::string(to_string(layer)) + " tile of " + std::to_string(bytes) + " bytes, expected " +
                            std::to_string(payload_bytes(level, layer)));
  }
  return static_cast<std::size_t>(e.first_tile + tile_index_in_level(layer, tx, ty, e.nx, e.ny));
}

Result<TilePlacement> place_tiles(PackLayout layout) {
  VISVOL_RETURN_IF_ERROR(validate(layout));
  TilePlacement p;
  p.layout = std::move(layout);
  // level, layer, ty, tx order, each tile on its own pages
  std::uint64_t offset = kPageBytes;  // after the header
  for (std::size_t l = 0; l < p.layout.levels.size(); ++l) {
    LevelEntry& level = p.layout.levels[l];
    level.first_tile = p.tiles.size();
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const TileGrid g = tile_grid(static_cast<Layer>(layer), level.nx, level.ny);
      const std::size_t bytes = round_up_to_page(p.payload_bytes(static_cast<int>(l), static_cast<Layer>(layer)));
      for (int ty = 0; ty < g.tiles_y; ++ty) {
        for (int tx = 0; tx < g.tiles_x; ++tx) {
          TileEntry t{};
          t.offset = offset;
          t.bytes = static_cast<std::uint32_t>(bytes);
          t.level = static_cast<std::uint16_t>(l);
          t.layer = static_cast<std::uint16_t>(layer);
          t.tx = static_cast<std::uint16_t>(tx);
          t.ty = static_cast<std::uint16_t>(ty);
          p.tiles.push_back(t);
          offset += bytes;
        }
      }
    }
  }
  p.tables_offset = offset;
  return p;
}

PackWriter::PackWriter(OutputFile out, TilePlacement placement)
    : out_(std::move(out)), path_(out_.path()), placement_(std::move(placement)) {
  written_.assign(placement_.tiles.size(), 0);
}

PackWriter::~PackWriter() = default;  // out_ removes an unfinished temporary

Status PackWriter::fail(Status status) {
  out_.discard();
  return status;
}

Result<std::unique_ptr<PackWriter>> PackWriter::create(const std::string& path, PackLayout layout) {
  return create(path, std::move(layout), false);
}

Result<std::unique_ptr<PackWriter>> PackWriter::create_shared(const std::string& path, PackLayout layout) {
  return create(path, std::move(layout), true);
}

Result<std::unique_ptr<PackWriter>> PackWriter::create(const std::string& path, PackLayout layout, bool shared) {
  Result<TilePlacement> placement = place_tiles(std::move(layout));
  if (!placement.ok()) return placement.status();
  Result<OutputFile> out = shared ? OutputFile::create_shared(path) : OutputFile::create(path);
  if (!out.ok()) return out.status();
  return std::unique_ptr<PackWriter>(new PackWriter(std::move(out).value(), std::move(placement).value()));
}

Status PackWriter::write_tile(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes) {
  if (out_.fd() < 0 || finished_) return Status(Errc::state, path_ + ": writer is closed");
  const Result<TilePlacement::Stored> stored =
      placement_.store(level, layer, tx, ty, payload, bytes,
                       [&](const void* data, std::size_t n, std::uint64_t at) { return out_.write_at(data, n, at); });
  if (!stored.ok()) {  // a tile that is not the layout's, or the write's own error (which names the file)
    const Status& st = stored.status();
    return st.code() == Errc::invalid_argument ? st.with_context(path_) : st;
  }
  placement_.tiles[stored->index].crc32c = stored->crc32c;
  written_[stored->index] = 1;
  return Status::ok_status();
}

Status PackWriter::add_written_tile(std::size_t index, std::uint32_t crc32c) {
  if (out_.fd() < 0 || finished_) return Status(Errc::state, path_ + ": writer is closed");
  if (index >= placement_.tiles.size()) {
    return invalid_argument(path_ + ": no tile " + std::to_string(index) + " (the pack has " +
                            std::to_string(placement_.tiles.size()) + ")");
  }
  placement_.tiles[index].crc32c = crc32c;
  written_[index] = 1;
  return Status::ok_status();
}

Status PackWriter::finish(const std::string& metadata_json) {
  if (out_.fd() < 0 || finished_) return Status(Errc::state, path_ + ": writer is closed");
  const std::vector<TileEntry>& tiles = placement_.tiles;
  const std::vector<LevelEntry>& levels = placement_.layout.levels;
  for (std::size_t n = 0; n < tiles.size(); ++n) {
    if (!written_[n]) {
      const TileEntry& t = tiles[n];
      return fail(Status(Errc::state, path_ + ": " + to_string(static_cast<Layer>(t.layer)) + " tile (" +
                                          std::to_string(t.tx) + ", " + std::to_string(t.ty) + ") of level " +
                                          std::to_string(t.level) + " was never written"));
    }
  }
  if (metadata_json.size() > kMaxMetadataBytes) {
    return fail(invalid_argument(path_ + ": metadata of " + std::to_string(metadata_json.size()) +
                                 " bytes, more than the " + std::to_string(kMaxMetadataBytes) + " a reader accepts"));
  }
  // tables and metadata, contiguous after the tiles
  std::vector<std::uint8_t> tables;
  auto append = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    tables.insert(tables.end(), b, b + n);
  };
  append(levels.data(), levels.size() * sizeof(LevelEntry));
  append(tiles.data(), tiles.size() * sizeof(TileEntry));
  append(metadata_json.data(), metadata_json.size());
  const std::uint64_t tables_offset = placement_.tables_offset;
  VISVOL_RETURN_IF_ERROR(out_.write_at(tables.data(), tables.size(), tables_offset));

  PackHeader h{};
  std::memcpy(h.magic, kPackMagic, sizeof h.magic);
  h.version = kPackVersion;
  h.header_bytes = sizeof(PackHeader);
  h.page_bytes = kPageBytes;
  h.level_count = static_cast<std::uint32_t>(levels.size());
  h.level_table_offset = tables_offset;
  h.level_entry_bytes = sizeof(LevelEntry);
  h.tile_entry_bytes = sizeof(TileEntry);
  h.tile_table_offset = tables_offset + levels.size() * sizeof(LevelEntry);
  h.tile_count = tiles.size();
  h.metadata_offset = h.tile_table_offset + tiles.size() * sizeof(TileEntry);
  h.metadata_bytes = metadata_json.size();
  h.file_bytes = h.metadata_offset + h.metadata_bytes;
  h.tile2d_posts = kTile2dPosts;
  h.brick_posts = kBrickPosts;
  h.visibility_encoding = static_cast<std::uint32_t>(placement_.layout.encoding);
  h.band_levels = static_cast<std::uint32_t>(placement_.layout.band_levels);
  h.band_offset_m = placement_.layout.band_offset_m;
  h.tables_crc32c = crc32c(tables.data(), tables.size());
  h.header_crc32c = crc32c(&h, offsetof(PackHeader, header_crc32c));
  VISVOL_RETURN_IF_ERROR(out_.write_at(&h, sizeof h, 0));
  if (::ftruncate(out_.fd(), static_cast<off_t>(h.file_bytes)) != 0) {
    return fail(output_error(path_ + ": cannot set the size of " + out_.write_path() + ": " + std::strerror(errno)));
  }
  file_bytes_ = h.file_bytes;
  VISVOL_RETURN_IF_ERROR(out_.commit());
  finished_ = true;
  return Status::ok_status();
}

}  // namespace visvol::storage
