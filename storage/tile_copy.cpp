#include "storage/tile_copy.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace visvol::storage {

std::uint64_t TileCopy::footprint(std::uint64_t tile_bytes) {
  static const auto page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  return (tile_bytes + page - 1) / page * page;
}

Result<TileCopy> TileCopy::read(const Pack& pack, const TileEntry& tile) {
  TileCopy c;
  c.bytes_ = static_cast<std::size_t>(tile.bytes);
  c.mapped_ = static_cast<std::size_t>(footprint(tile.bytes));
  if (c.mapped_ == 0) return Status(Errc::corrupt, pack.path() + ": " + Pack::describe(tile) + " is empty");
  void* m = ::mmap(nullptr, c.mapped_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) {
    return Status(Errc::resource,
                  pack.path() + ": " + Pack::describe(tile) + ": no memory for a copy: " + std::strerror(errno));
  }
  c.data_ = static_cast<std::uint8_t*>(m);
  VISVOL_RETURN_IF_ERROR(pack.read_tile(tile, c.data_));
  return c;
}

TileCopy::~TileCopy() {
  if (data_ != nullptr) ::munmap(data_, mapped_);  // unlocks it too
}

TileCopy::TileCopy(TileCopy&& other) noexcept { *this = std::move(other); }

TileCopy& TileCopy::operator=(TileCopy&& other) noexcept {
  if (this == &other) return *this;
  if (data_ != nullptr) ::munmap(data_, mapped_);
  data_ = other.data_;
  bytes_ = other.bytes_;
  mapped_ = other.mapped_;
  other.data_ = nullptr;
  other.bytes_ = other.mapped_ = 0;
  return *this;
}

std::string TileCopy::lock() {
  if (data_ == nullptr || ::mlock(data_, mapped_) == 0) return {};
  return std::strerror(errno);
}

Result<PackLevel> LevelCopies::unset(std::shared_ptr<const Pack> pack, int level) {
  return PackLevel::open_unset(std::move(pack), level);
}

Status LevelCopies::copy_heights(PackLevel& level, std::vector<TileCopy>& out, const Lock& lock) {
  const Pack& p = level.pack();
  const LevelEntry& e = p.level(level.level());
  const TileGrid g = tile_grid(Layer::height, e.nx, e.ny);
  for (int ty = 0; ty < g.tiles_y; ++ty) {
    for (int tx = 0; tx < g.tiles_x; ++tx) {
      const TileEntry& tile = p.tile(level.level(), Layer::height, tx, ty);
      Result<TileCopy> c = TileCopy::read(p, tile);
      if (!c.ok()) return c.status();
      if (lock) lock(*c, tile);
      level.height_[static_cast<std::size_t>(ty * g.tiles_x + tx)] = c->data();
      out.push_back(std::move(*c));
    }
  }
  return Status::ok_status();
}

Status LevelCopies::copy_brick(PackLevel& level, std::size_t b, TileCopy& visibility, TileCopy& tff, const Lock& lock) {
  const Pack& p = level.pack();
  const auto bricks_x = static_cast<std::size_t>(level.bricks_x_);
  const int bx = static_cast<int>(b % bricks_x), by = static_cast<int>(b / bricks_x);
  const TileEntry& vt = p.tile(level.level(), Layer::visibility, bx, by);
  const TileEntry& tt = p.tile(level.level(), Layer::tff, bx, by);
  Result<TileCopy> v = TileCopy::read(p, vt);
  if (!v.ok()) return v.status();
  Result<TileCopy> t = TileCopy::read(p, tt);
  if (!t.ok()) return t.status();
  if (lock) {
    lock(*v, vt);
    lock(*t, tt);
  }
  level.visibility_[b] = v->data();
  level.tff_tiles_[b] = t->data();
  visibility = std::move(*v);
  tff = std::move(*t);
  return Status::ok_status();
}

void LevelCopies::drop_brick(PackLevel& level, std::size_t b, TileCopy& visibility, TileCopy& tff) {
  level.visibility_[b] = nullptr;
  level.tff_tiles_[b] = nullptr;
  visibility = TileCopy();
  tff = TileCopy();
}

std::uint64_t LevelCopies::heights_footprint(const Pack& pack, int level) {
  const LevelEntry& e = pack.level(level);
  const TileGrid g = tile_grid(Layer::height, e.nx, e.ny);
  std::uint64_t total = 0;
  for (int ty = 0; ty < g.tiles_y; ++ty)
    for (int tx = 0; tx < g.tiles_x; ++tx) total += TileCopy::footprint(pack.tile(level, Layer::height, tx, ty).bytes);
  return total;
}

std::uint64_t LevelCopies::brick_footprint(const Pack& pack, int level, int bx, int by) {
  return TileCopy::footprint(pack.tile(level, Layer::visibility, bx, by).bytes) +
         TileCopy::footprint(pack.tile(level, Layer::tff, bx, by).bytes);
}

}  // namespace visvol::storage
