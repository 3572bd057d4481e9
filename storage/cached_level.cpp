#include "storage/cached_level.hpp"

#include <algorithm>

namespace visvol::storage {

Result<CachedLevel> CachedLevel::open(std::shared_ptr<const Pack> pack, int level, int max_bricks) {
  if (max_bricks < 1) return invalid_argument("cached level: max_bricks must be at least 1");
  Result<PackLevel> unset = PackLevel::open_unset(std::move(pack), level);
  if (!unset.ok()) return unset.status();
  CachedLevel c(std::move(*unset));
  const Pack& p = c.level_.pack();
  const LevelEntry& e = p.level(level);
  const TileGrid hg = tile_grid(Layer::height, e.nx, e.ny);
  for (int ty = 0; ty < hg.tiles_y; ++ty) {
    for (int tx = 0; tx < hg.tiles_x; ++tx) {
      Result<TileCopy> h = TileCopy::read(p, p.tile(level, Layer::height, tx, ty));
      if (!h.ok()) return h.status();
      c.level_.height_[static_cast<std::size_t>(ty * hg.tiles_x + tx)] = h->data();
      c.heights_.push_back(std::move(*h));
    }
  }
  const TileGrid bg = tile_grid(Layer::visibility, e.nx, e.ny);
  c.bricks_x_ = bg.tiles_x;
  c.max_slots_ = static_cast<std::size_t>(std::min<std::int64_t>(max_bricks, bg.count()));
  c.slot_of_.assign(static_cast<std::size_t>(bg.count()), kUnread);
  c.slots_.reserve(c.max_slots_);
  return c;
}

bool CachedLevel::load(std::size_t b) const {
  const Pack& p = level_.pack();
  const int level = level_.level();
  const int bx = static_cast<int>(b % static_cast<std::size_t>(bricks_x_));
  const int by = static_cast<int>(b / static_cast<std::size_t>(bricks_x_));
  Result<TileCopy> v = TileCopy::read(p, p.tile(level, Layer::visibility, bx, by));
  Result<TileCopy> t = v.ok() ? TileCopy::read(p, p.tile(level, Layer::tff, bx, by)) : Result<TileCopy>(v.status());
  if (!t.ok()) {
    slot_of_[b] = kUnreadable;
    ++failures_;
    last_error_ = t.status();
    return false;
  }
  std::size_t s = slots_.size();
  if (s == max_slots_) {  // the least recently used goes
    s = static_cast<std::size_t>(
        std::min_element(slots_.begin(), slots_.end(), [](const Slot& a, const Slot& z) { return a.used < z.used; }) -
        slots_.begin());
    const std::size_t old = slots_[s].brick;
    slot_of_[old] = kUnread;
    level_.visibility_[old] = nullptr;
    level_.tff_tiles_[old] = nullptr;
  } else {
    slots_.emplace_back();
  }
  Slot& slot = slots_[s];
  slot.brick = b;
  slot.used = ++clock_;
  slot.visibility = std::move(*v);
  slot.tff = std::move(*t);
  level_.visibility_[b] = slot.visibility.data();
  level_.tff_tiles_[b] = slot.tff.data();
  slot_of_[b] = static_cast<int>(s);
  return true;
}

std::uint64_t CachedLevel::bytes(const Pack& p, int level, int max_bricks) {
  const LevelEntry& e = p.level(level);
  std::uint64_t total = 0, largest_brick = 0;
  const TileGrid hg = tile_grid(Layer::height, e.nx, e.ny);
  for (int ty = 0; ty < hg.tiles_y; ++ty)
    for (int tx = 0; tx < hg.tiles_x; ++tx) total += p.tile(level, Layer::height, tx, ty).bytes;
  const TileGrid bg = tile_grid(Layer::visibility, e.nx, e.ny);
  for (int by = 0; by < bg.tiles_y; ++by) {
    for (int bx = 0; bx < bg.tiles_x; ++bx) {
      largest_brick =
          std::max<std::uint64_t>(largest_brick, std::uint64_t{p.tile(level, Layer::visibility, bx, by).bytes} +
                                                     p.tile(level, Layer::tff, bx, by).bytes);
    }
  }
  return total + largest_brick * static_cast<std::uint64_t>(std::min<std::int64_t>(max_bricks, bg.count()));
}

}  // namespace visvol::storage
