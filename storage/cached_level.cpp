#include "storage/cached_level.hpp"

#include <algorithm>

namespace visvol::storage {

Result<CachedLevel> CachedLevel::open(std::shared_ptr<const Pack> pack, int level, int max_bricks) {
  if (max_bricks < 1) return invalid_argument("cached level: max_bricks must be at least 1");
  Result<PackLevel> unset = LevelCopies::unset(std::move(pack), level);
  if (!unset.ok()) return unset.status();
  CachedLevel c(std::move(*unset));
  VISVOL_RETURN_IF_ERROR(LevelCopies::copy_heights(c.level_, c.heights_));
  const LevelEntry& e = c.level_.pack().level(level);
  const TileGrid bg = tile_grid(Layer::visibility, e.nx, e.ny);
  c.bricks_x_ = bg.tiles_x;
  c.max_slots_ = static_cast<std::size_t>(std::min<std::int64_t>(max_bricks, bg.count()));
  c.slot_of_.assign(static_cast<std::size_t>(bg.count()), kUnread);
  c.slots_.reserve(c.max_slots_);
  return c;
}

bool CachedLevel::load(std::size_t b) const {
  TileCopy visibility, tff;
  const Status read = LevelCopies::copy_brick(level_, b, visibility, tff);
  if (!read.ok()) {
    slot_of_[b] = kUnreadable;
    ++failures_;
    last_error_ = read;
    return false;
  }
  std::size_t s = slots_.size();
  if (s == max_slots_) {  // the least recently used goes
    s = static_cast<std::size_t>(
        std::min_element(slots_.begin(), slots_.end(), [](const Slot& a, const Slot& z) { return a.used < z.used; }) -
        slots_.begin());
    slot_of_[slots_[s].brick] = kUnread;
    LevelCopies::drop_brick(level_, slots_[s].brick, slots_[s].visibility, slots_[s].tff);
  } else {
    slots_.emplace_back();
  }
  Slot& slot = slots_[s];
  slot.brick = b;
  slot.used = ++clock_;
  slot.visibility = std::move(visibility);  // the pages, and the level's pointers into them, stay
  slot.tff = std::move(tff);
  slot_of_[b] = static_cast<int>(s);
  return true;
}

std::uint64_t CachedLevel::bytes(const Pack& p, int level, int max_bricks) {
  const LevelEntry& e = p.level(level);
  std::uint64_t largest_brick = 0;
  const TileGrid bg = tile_grid(Layer::visibility, e.nx, e.ny);
  for (int by = 0; by < bg.tiles_y; ++by)
    for (int bx = 0; bx < bg.tiles_x; ++bx)
      largest_brick = std::max(largest_brick, LevelCopies::brick_footprint(p, level, bx, by));
  return LevelCopies::heights_footprint(p, level) +
         largest_brick * static_cast<std::uint64_t>(std::min<std::int64_t>(max_bricks, bg.count()));
}

}  // namespace visvol::storage
