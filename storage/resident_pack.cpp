#include "storage/resident_pack.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "fields/sampler.hpp"

namespace visvol::storage {

namespace {

constexpr std::uint8_t kAbsent = 0;
constexpr std::uint8_t kResident = 1;

double mib(std::uint64_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); }

std::string mib_text(std::uint64_t bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", mib(bytes));
  return b;
}

}  // namespace

Status validate(const ResidentConfig& c) {
  if (c.budget_bytes == 0) return invalid_argument("tile budget: must be above 0 MiB");
  if (!(c.margin_m >= 0 && c.margin_m <= 1e6)) {
    return invalid_argument("tile margin: " + std::to_string(c.margin_m) + " m is outside 0..1000000 m");
  }
  if (!(c.poll_interval_s >= 0.001 && c.poll_interval_s <= 10)) {
    return invalid_argument("pager interval: " + std::to_string(c.poll_interval_s) + " s is outside 0.001..10 s");
  }
  return {};
}

// ---- the real-time view ------------------------------------------------------

bool ResidentLevel::resident(int i, int j) const {
  if (coarser_ == nullptr) return true;
  const std::size_t b = static_cast<std::size_t>((j / kBrickPosts) * bricks_x_ + i / kBrickPosts);
  return state_[b].load(std::memory_order_seq_cst) == kResident;  // see ResidentPack::tick_done
}

bool ResidentLevel::resident(int i0, int j0, int i1, int j1) const {
  if (coarser_ == nullptr) return true;
  // columns are never negative: unsigned division is a shift
  const unsigned bx0 = static_cast<unsigned>(i0) / kBrickPosts, bx1 = static_cast<unsigned>(i1) / kBrickPosts;
  const unsigned by0 = static_cast<unsigned>(j0) / kBrickPosts, by1 = static_cast<unsigned>(j1) / kBrickPosts;
  for (unsigned by = by0; by <= by1; ++by) {
    for (unsigned bx = bx0; bx <= bx1; ++bx) {
      if (state_[by * static_cast<std::size_t>(bricks_x_) + bx].load(std::memory_order_seq_cst) != kResident) {
        return false;
      }
    }
  }
  return true;
}

float ResidentLevel::voxel(int i, int j, int k) const {
  if (resident(i, j)) return level_->voxel(i, j, k);
  fallbacks_->fetch_add(1, std::memory_order_relaxed);
  const fields::VolumeGeometry& g = level_->geometry();
  const fields::FieldSampler<ResidentLevel> coarse(*coarser_);
  return static_cast<float>(coarse.visibility(g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, g.z_of(k)));
}

fields::TffSample ResidentLevel::tff(int i, int j, int b) const {
  if (resident(i, j)) return level_->tff(i, j, b);
  fallbacks_->fetch_add(1, std::memory_order_relaxed);
  // the band sample's world point: band b above this level's own terrain
  const fields::VolumeGeometry& g = level_->geometry();
  const fields::TffParams& p = level_->tff_params();
  const double z = level_->post(i, j) - p.band_offset_m + b * p.step_m();
  const fields::FieldSampler<ResidentLevel> coarse(*coarser_);
  return coarse.terrain_force(g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, z);
}

// ---- the real-time sampler -----------------------------------------------------

ResidentSampler::ResidentSampler(const ResidentLevel& level) : level_(&level) {
  for (const ResidentLevel* l = &level; l != nullptr && count_ < kMaxLodLevels; l = l->coarser()) {
    chain_[count_] = l;
    samplers_[count_] = fields::FieldSampler<PackLevelRef>(PackLevelRef(l->pack_level()));
    ++count_;
  }
}

int ResidentSampler::pick(double x, double y, Sampler::Cell& cell, Sampler::Cell* finest) const {
  for (int n = 0; n + 1 < count_; ++n) {
    const fields::VolumeGeometry& g = chain_[n]->geometry();
    cell = samplers_[n].cell(x, y);
    if (n == 0 && finest != nullptr) *finest = cell;
    // the columns a gradient reads: the cell's corners and their neighbours
    if (chain_[n]->resident(std::max(cell.i - 1, 0), std::max(cell.j - 1, 0), std::min(cell.i + 2, g.nx - 1),
                            std::min(cell.j + 2, g.ny - 1))) {
      return n;
    }
    chain_[n]->fallbacks_->fetch_add(1, std::memory_order_relaxed);
  }
  cell = samplers_[count_ - 1].cell(x, y);
  if (count_ == 1 && finest != nullptr) *finest = cell;
  return count_ - 1;
}

fields::PointSample ResidentSampler::sample(double x, double y, double z, bool with_gradient,
                                            bool with_terrain_force) const {
  Sampler::Cell cell, finest;
  const int n = pick(x, y, cell, &finest);
  fields::PointSample s = samplers_[n].sample(cell, z, with_gradient, with_terrain_force);
  // heights always come from the level given (its ground differs from a coarser one's)
  if (n != 0) s.height_m = samplers_[0].height(finest);
  return s;
}

// ---- the pack ----------------------------------------------------------------

ResidentPack::ResidentPack(std::shared_ptr<const Pack> pack, const ResidentConfig& config)
    : pack_(std::move(pack)), config_(config) {}

Result<std::unique_ptr<ResidentPack>> ResidentPack::create(std::shared_ptr<const Pack> pack,
                                                           const ResidentConfig& config) {
  VISVOL_RETURN_IF_ERROR(validate(config));
  std::unique_ptr<ResidentPack> r(new ResidentPack(std::move(pack), config));
  VISVOL_RETURN_IF_ERROR(r->init());
  return r;
}

Status ResidentPack::init() {
  const int n = pack_->level_count();
  for (int l = 0; l < n; ++l) {
    Result<PackLevel> level = LevelCopies::unset(pack_, l);
    if (!level.ok()) return level.status();
    levels_.push_back(std::move(*level));
  }
  stats_.budget_bytes = config_.budget_bytes;
  stats_.pack_bytes = pack_->file_bytes();
  // the minimum: every level's heights and the coarsest level's bricks
  std::uint64_t minimum = 0;
  for (int l = 0; l < n; ++l) {
    const LevelEntry& e = pack_->level(l);
    minimum += LevelCopies::heights_footprint(*pack_, l);
    auto s = std::make_unique<LevelState>();
    const TileGrid bg = tile_grid(Layer::visibility, e.nx, e.ny);
    s->bricks_x = bg.tiles_x;
    s->bricks_y = bg.tiles_y;
    s->state = std::make_unique<std::atomic<std::uint8_t>[]>(static_cast<std::size_t>(bg.count()));
    s->copies.resize(2 * static_cast<std::size_t>(bg.count()));
    s->refused.assign(static_cast<std::size_t>(bg.count()), 0);
    s->target.assign(static_cast<std::size_t>(bg.count()), 0);
    for (int by = 0; by < bg.tiles_y; ++by) {
      for (int bx = 0; bx < bg.tiles_x; ++bx) {
        s->bricks.push_back({LevelCopies::brick_footprint(*pack_, l, bx, by)});
        s->state[s->bricks.size() - 1].store(kAbsent, std::memory_order_relaxed);
        if (l == n - 1) minimum += s->bricks.back().bytes;
      }
    }
    stats_.brick_counts.push_back(static_cast<std::uint32_t>(bg.count()));
    stats_.resident_bricks.push_back(0);
    state_.push_back(std::move(s));
  }
  stats_.minimum_bytes = minimum;
  if (minimum > config_.budget_bytes) {
    return Status(Errc::resource, "tile budget " + mib_text(config_.budget_bytes) + " cannot hold the minimum " +
                                      mib_text(minimum) + " of " + pack_->path() +
                                      " (the heights of every level and the coarsest level's field); raise the budget");
  }
  // the views: each falls back to the next coarser
  views_.resize(static_cast<std::size_t>(n));
  for (int l = n - 1; l >= 0; --l) {
    ResidentLevel& v = views_[static_cast<std::size_t>(l)];
    LevelState& s = *state_[static_cast<std::size_t>(l)];
    v.level_ = &levels_[static_cast<std::size_t>(l)];
    v.state_ = s.state.get();
    v.bricks_x_ = s.bricks_x;
    v.coarser_ = l == n - 1 ? nullptr : &views_[static_cast<std::size_t>(l + 1)];
    v.fallbacks_ = &s.fallbacks;
  }
  // copy and lock the minimum now
  for (int l = 0; l < n; ++l) {
    VISVOL_RETURN_IF_ERROR(LevelCopies::copy_heights(levels_[static_cast<std::size_t>(l)], heights_, lock_copy()));
  }
  LevelState& coarsest = *state_.back();
  for (std::size_t b = 0; b < coarsest.bricks.size(); ++b) {
    VISVOL_RETURN_IF_ERROR(load_brick(n - 1, b));
    coarsest.state[b].store(kResident, std::memory_order_release);
    coarsest.target[b] = 1;
  }
  stats_.resident_bytes = minimum;
  stats_.resident_bricks.back() = static_cast<std::uint32_t>(coarsest.bricks.size());
  return {};
}

ResidentPack::~ResidentPack() { stop_pager(); }

// Each copy locked where asked; a copy that cannot be is counted and named.
LevelCopies::Lock ResidentPack::lock_copy() {
  if (!config_.lock) return {};
  return [this](TileCopy& c, const TileEntry& tile) {
    const std::string why = c.lock();
    if (why.empty()) return;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.lock_failures;
    stats_.last_error =
        Pack::describe(tile) + ": not locked (mlock: " + why + "); it stays resident while memory lasts";
  };
}

// Before the brick is marked resident: the state's release store publishes
// the pointers with the copies.
Status ResidentPack::load_brick(int level, std::size_t b) {
  LevelState& s = *state_[static_cast<std::size_t>(level)];
  return LevelCopies::copy_brick(levels_[static_cast<std::size_t>(level)], b, s.copies[2 * b], s.copies[2 * b + 1],
                                 lock_copy());
}

void ResidentPack::drop_evicted() {
  for (const auto& [l, b] : evicted_) drop_brick(l, b);
  evicted_.clear();
}

// After the brick was marked absent and the readers have passed it.
void ResidentPack::drop_brick(int level, std::size_t b) {
  LevelState& s = *state_[static_cast<std::size_t>(level)];
  LevelCopies::drop_brick(levels_[static_cast<std::size_t>(level)], b, s.copies[2 * b], s.copies[2 * b + 1]);
}

bool ResidentPack::wait_for_readers() {
  // seq_cst: after the evictions' stores in the total order (see tick_done)
  const std::uint64_t start = epoch_.load(std::memory_order_seq_cst);
  while (reader_active_.load(std::memory_order_acquire) && epoch_.load(std::memory_order_seq_cst) < start + 2) {
    if (stop_.load(std::memory_order_acquire)) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

void ResidentPack::plan(const WorldBox& box, std::uint64_t budget_left) {
  const int n = level_count();
  bool short_of_budget = false;
  struct Candidate {
    double distance2;
    std::size_t brick;
  };
  std::vector<Candidate> candidates;
  for (int l = n - 2; l >= 0; --l) {
    LevelState& s = *state_[static_cast<std::size_t>(l)];
    std::fill(s.target.begin(), s.target.end(), 0);
    if (!have_focus_ || short_of_budget) continue;
    const fields::VolumeGeometry& g = levels_[static_cast<std::size_t>(l)].geometry();
    const double brick_m = kBrickPosts * g.spacing_m;
    const double m = config_.margin_m;
    // clamped before the conversion: a far-off focus is a brick beyond the edge
    auto col = [&](double x) {
      return static_cast<int>(std::clamp(std::floor((x - g.origin_x) / brick_m), -1.0, double(s.bricks_x)));
    };
    auto row = [&](double y) {
      return static_cast<int>(std::clamp(std::floor((g.origin_y - y) / brick_m), -1.0, double(s.bricks_y)));
    };
    const int bx0 = std::max(0, col(box.x0_m - m)), bx1 = std::min(s.bricks_x - 1, col(box.x1_m + m));
    const int by0 = std::max(0, row(box.y1_m + m)), by1 = std::min(s.bricks_y - 1, row(box.y0_m - m));
    const double cx = 0.5 * (box.x0_m + box.x1_m), cy = 0.5 * (box.y0_m + box.y1_m);
    candidates.clear();
    for (int by = by0; by <= by1; ++by) {
      for (int bx = bx0; bx <= bx1; ++bx) {
        const double x = g.origin_x + (bx + 0.5) * brick_m, y = g.origin_y - (by + 0.5) * brick_m;
        candidates.push_back(
            {(x - cx) * (x - cx) + (y - cy) * (y - cy), static_cast<std::size_t>(by * s.bricks_x + bx)});
      }
    }
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.distance2 < b.distance2; });
    for (const Candidate& c : candidates) {
      if (s.refused[c.brick]) continue;
      const std::uint64_t cost = s.bricks[c.brick].bytes;
      if (cost > budget_left) {
        short_of_budget = true;
        break;
      }
      budget_left -= cost;
      s.target[c.brick] = 1;
    }
  }
  if (short_of_budget) {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.budget_short;
  }
}

Status ResidentPack::update() {
  std::lock_guard<std::mutex> guard(update_mutex_);
  const WorldBox* box = focus_.take();
  // a focus that is not finite (a rope gone bad) keeps the last one
  if (box != nullptr && std::isfinite(box->x0_m + box->y0_m + box->x1_m + box->y1_m)) {
    last_focus_ = *box;
    have_focus_ = true;
  }
  std::uint64_t minimum = 0, resident = 0;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    minimum = stats_.minimum_bytes;
    resident = stats_.resident_bytes;
  }
  plan(last_focus_, config_.budget_bytes - minimum);
  const int n = level_count();
  // evict first, so that the budget holds at every moment
  std::uint64_t evicted = 0;
  for (int l = 0; l < n - 1; ++l) {
    LevelState& s = *state_[static_cast<std::size_t>(l)];
    for (std::size_t b = 0; b < s.bricks.size(); ++b) {
      if (!s.target[b] && s.state[b].load(std::memory_order_relaxed) == kResident) {
        s.state[b].store(kAbsent, std::memory_order_seq_cst);  // see tick_done
        evicted_.emplace_back(l, b);
        resident -= s.bricks[b].bytes;
        ++evicted;
      }
    }
  }
  if (!evicted_.empty() && !wait_for_readers()) {
    // stopping: what was marked absent is dropped by the next pass, or with
    // the pack; the figures say it is gone already
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.bricks_evicted += evicted;
    stats_.resident_bytes = resident;
    return {};
  }
  drop_evicted();
  std::uint64_t loaded = 0, corrupt = 0;
  std::string error;
  for (int l = n - 2; l >= 0; --l) {  // coarser first: the wider fallback comes in soonest
    LevelState& s = *state_[static_cast<std::size_t>(l)];
    for (std::size_t b = 0; b < s.bricks.size(); ++b) {
      if (!s.target[b] || s.state[b].load(std::memory_order_relaxed) == kResident) continue;
      if (stop_.load(std::memory_order_acquire)) break;
      const Brick& brick = s.bricks[b];
      const Status st = load_brick(l, b);
      if (!st.ok()) {
        s.target[b] = 0;
        s.refused[b] = 1;
        ++corrupt;
        error = st.message();
        continue;
      }
      s.state[b].store(kResident, std::memory_order_release);
      resident += brick.bytes;
      ++loaded;
    }
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.passes;
  stats_.bricks_loaded += loaded;
  stats_.bricks_evicted += evicted;
  stats_.corrupt_bricks += corrupt;
  if (!error.empty()) stats_.last_error = error;
  stats_.resident_bytes = resident;
  for (int l = 0; l < n; ++l) {
    const LevelState& s = *state_[static_cast<std::size_t>(l)];
    std::uint32_t count = 0;
    for (std::size_t b = 0; b < s.bricks.size(); ++b) count += s.state[b].load(std::memory_order_relaxed) == kResident;
    stats_.resident_bricks[static_cast<std::size_t>(l)] = count;
  }
  return {};
}

void ResidentPack::start_pager() {
  if (pager_.joinable()) return;
  stop_.store(false);
  pager_ = std::thread([this] { pager_loop(); });
}

void ResidentPack::stop_pager() {
  stop_.store(true, std::memory_order_release);
  if (pager_.joinable()) pager_.join();
}

void ResidentPack::pager_loop() {
  const auto interval = std::chrono::duration<double>(config_.poll_interval_s);
  while (!stop_.load(std::memory_order_acquire)) {
    (void)update();  // problems are counted in stats(); a pass never fails as a whole
    std::this_thread::sleep_for(interval);
  }
}

std::uint64_t ResidentPack::fallbacks() const {
  std::uint64_t sum = 0;
  for (const auto& s : state_) sum += s->fallbacks.load(std::memory_order_relaxed);
  return sum;
}

ResidentStats ResidentPack::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

}  // namespace visvol::storage
