#include "fields/visibility_builder.hpp"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <new>
#include <sstream>

#include "fields/hull_kernel.hpp"
#include "fields/worker_pool.hpp"

namespace visvol::fields {

namespace {

constexpr std::size_t kMiB = 1024 * 1024;
constexpr int kMaxBatchRows = 16;

std::size_t window_rows(int ny, int radius, int batch) {
  return static_cast<std::size_t>(std::min(ny, 2 * radius + batch));
}

// Finished rows are turned to the sink's order `batch` at a time, in parallel.
std::size_t staging_for(int batch, std::size_t slab_bytes) { return static_cast<std::size_t>(batch) * slab_bytes; }

// Everything the two phases share, sized once per build.
struct Build {
  const Heightfield& hf;
  const FieldParams& params;
  VolumeGeometry geom;
  BuildPlan plan;
  int radius = 0;
  int win = 0;                // rows in the histogram window
  std::size_t slab_ints = 0;  // nx * (nz + 1): one row's histogram, column-major, junk level last
  LevelMap levels;
  LevelRowLayout layout;
  PaddedTerrain terrain;
  HullTable table;
  ObserverWeights weights;
  std::vector<std::int32_t> weight_padded;  // per observer, chunk-padded rows (0 past nx)
  std::vector<std::int32_t> top_level;      // cube: first level above the range, per observer
  std::vector<float> eye_m;                 // per observer, chunk-padded rows
  std::vector<float> span_m;                // sphere: half height per offset (2r+1)^2
  std::vector<std::uint8_t> hull_levels;    // one batch of observer rows
  std::vector<std::int32_t> window;         // win slabs
  std::vector<std::uint64_t> cells_per_worker;

  Build(const Heightfield& h, const FieldParams& p, const BuildPlan& pl)
      : hf(h),
        params(p),
        geom(volume_geometry(h, p)),
        plan(pl),
        radius(pl.radius_posts),
        win(static_cast<int>(window_rows(h.ny, pl.radius_posts, pl.batch_rows))),
        slab_ints(static_cast<std::size_t>(geom.nz + 1) * static_cast<std::size_t>(h.nx)),
        levels{static_cast<float>(geom.z0_m), static_cast<float>(1.0 / geom.dz_m), geom.nz},
        layout(h.nx, h.ny, pl.radius_posts),
        terrain(pad_terrain(h, geom, pl.radius_posts)),
        table(pl.radius_posts, p.exact_rings, h.spacing_m, p.curvature_coeff, p.range_shape,
              p.range_posts * h.spacing_m, terrain.stride) {}

  int padded_width() const { return layout.chunks * kLanes; }
  std::size_t padded_index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(padded_width()) + static_cast<std::size_t>(i);
  }
  std::int32_t* slab(int y) { return window.data() + static_cast<std::size_t>(y % win) * slab_ints; }
  const std::int32_t* slab(int y) const { return window.data() + static_cast<std::size_t>(y % win) * slab_ints; }
};

void prepare_observers(Build& b) {
  const std::vector<float> area = area_factor(b.hf);
  b.weights = observer_weights(b.hf, area, b.params.weights);
  const std::size_t n = static_cast<std::size_t>(b.padded_width()) * static_cast<std::size_t>(b.hf.ny);
  b.weight_padded.assign(n, 0);
  b.top_level.assign(n, b.geom.nz);
  b.eye_m.assign(n, 0.0f);
  const double cube_height = 2.0 * b.params.range_posts * b.hf.spacing_m;
  for (int j = 0; j < b.hf.ny; ++j) {
    for (int i = 0; i < b.padded_width(); ++i) {
      const int ic = std::min(i, b.hf.nx - 1);  // lanes past the grid copy the last post
      const double ground = b.hf.at(ic, j);
      const std::size_t pi = b.padded_index(i, j);
      b.eye_m[pi] = static_cast<float>(ground + b.params.eye_height_m);
      if (i < b.hf.nx) {
        b.weight_padded[pi] =
            b.weights
                .weight[static_cast<std::size_t>(j) * static_cast<std::size_t>(b.hf.nx) + static_cast<std::size_t>(i)];
      }
      if (b.params.range_shape == RangeShape::cube) {
        const double top = std::floor((ground + cube_height - b.geom.z0_m) / b.geom.dz_m) + 1;
        b.top_level[pi] = static_cast<std::int32_t>(std::clamp(top, 0.0, double(b.geom.nz)));
      }
    }
  }
  if (b.params.range_shape == RangeShape::sphere) {
    const int side = 2 * b.radius + 1;
    b.span_m.assign(static_cast<std::size_t>(side) * static_cast<std::size_t>(side), -1.0e30f);
    const double range_m = b.params.range_posts * b.hf.spacing_m;
    for (int dy = -b.radius; dy <= b.radius; ++dy) {
      for (int dx = -b.radius; dx <= b.radius; ++dx) {
        const double d = std::hypot(double(dx), double(dy)) * b.hf.spacing_m;
        if (d <= range_m) {
          b.span_m[static_cast<std::size_t>(dy + b.radius) * static_cast<std::size_t>(side) +
                   static_cast<std::size_t>(dx + b.radius)] = static_cast<float>(std::sqrt(range_m * range_m - d * d));
        }
      }
    }
  }
}

// Lowest level each observer's range admits: its ground for the cube.
std::int32_t floor_level(const Build& b, double ground_m) {
  if (b.params.range_shape != RangeShape::cube) return 0;
  const double k = std::ceil((ground_m - b.geom.z0_m) / b.geom.dz_m);
  return static_cast<std::int32_t>(std::clamp(k, 0.0, double(b.geom.nz)));
}

// Phase 1 for one chunk of observers.
void hull_phase(Build& b, int batch_first, int item, std::vector<float>& ring_a, std::vector<float>& ring_b) {
  const int py = batch_first + item / b.layout.chunks;
  const int chunk = item % b.layout.chunks;
  ObserverChunk oc;
  oc.px0 = chunk * kLanes;
  oc.py = py;
  for (int l = 0; l < kLanes; ++l) {
    const std::size_t pi = b.padded_index(oc.px0 + l, py);
    oc.eye_m[l] = b.eye_m[pi];
    oc.floor_level[l] = floor_level(b, b.hf.at(std::min(oc.px0 + l, b.hf.nx - 1), py));
    assert(oc.floor_level[l] >= 0 && oc.floor_level[l] <= b.levels.nz);  // the kernel's preconditions
  }
  assert(b.levels.nz <= kMaxHeightLevels);
  std::uint8_t* out =
      b.hull_levels.data() + static_cast<std::size_t>(py - batch_first) * b.layout.bytes_per_observer_row();
  hull_levels_chunk(b.table, b.terrain, b.layout, b.levels, b.params.range_shape, oc, ring_a.data(), ring_b.data(),
                    out);
}

// Phase 2: adds the contributions of the batch's observer rows to target row
// y. The row's histogram is column-major ((nz + 1) levels per column, the last
// one junk), and each column gathers its observers in turn, so every update
// hits the same small column in L1.
std::uint64_t scatter_row(Build& b, int batch_first, int batch_rows, int y) {
  std::int32_t* slab = b.slab(y);
  const int nx = b.hf.nx;
  const int nz = b.geom.nz;
  const std::size_t col_ints = static_cast<std::size_t>(nz + 1);
  const bool sphere = b.params.range_shape == RangeShape::sphere;
  const int side = 2 * b.radius + 1;
  const float inv_dz = static_cast<float>(1.0 / b.geom.dz_m);
  const float z0 = static_cast<float>(b.geom.z0_m);
  std::uint64_t cells = 0;
  const int py_lo = std::max(batch_first, y - b.radius);
  const int py_hi = std::min(batch_first + batch_rows - 1, y + b.radius);
  for (int py = py_lo; py <= py_hi; ++py) {
    const std::uint8_t* block =
        b.hull_levels.data() + static_cast<std::size_t>(py - batch_first) * b.layout.bytes_per_observer_row();
    const std::int32_t* w = b.weight_padded.data() + b.padded_index(0, py);
    const std::int32_t* top = b.top_level.data() + b.padded_index(0, py);
    const float* eye = b.eye_m.data() + b.padded_index(0, py);
    const bool open_top = !sphere && std::all_of(top, top + b.padded_width(), [&](std::int32_t t) { return t >= nz; });
    const float* span_row =
        sphere
            ? b.span_m.data() + static_cast<std::size_t>(y - py + b.radius) * static_cast<std::size_t>(side) + b.radius
            : nullptr;
    // Level of observer px over target column x.
    auto level = [&](int px, int x) {
      const int c = px / kLanes, px0 = c * kLanes;
      return block[b.layout.offset(py, y, c, x - px - b.layout.first_dx(px0)) + static_cast<std::size_t>(px - px0)];
    };
    auto add = [&](int px, int x) {
      std::int32_t* col = slab + static_cast<std::size_t>(x) * col_ints;
      const int kl = level(px, x);
      col[kl] += w[px];
      if (open_top) return;
      int kh = top[px];
      if (sphere) {
        const float q = std::floor((eye[px] + span_row[x - px] - z0) * inv_dz) + 1;
        kh = static_cast<int>(std::clamp(q, 0.0f, static_cast<float>(nz)));
      }
      col[std::max(kl, kh)] -= w[px];  // the range ends (level nz is junk)
    };
    int x = 0;
    if (open_top) {
      // Four target columns at a time: four independent update chains, where
      // one column alone would chain on repeated levels.
      for (; x + 3 < nx; x += 4) {
        std::int32_t* c0 = slab + static_cast<std::size_t>(x) * col_ints;
        std::int32_t* c1 = c0 + col_ints;
        std::int32_t* c2 = c1 + col_ints;
        std::int32_t* c3 = c2 + col_ints;
        const int lo = std::max(0, x - b.radius), hi = std::min(nx - 1, x + 3 + b.radius);
        const int all_lo = std::max(0, x + 3 - b.radius), all_hi = std::min(nx - 1, x + b.radius);
        cells += 4 * static_cast<std::uint64_t>(all_hi - all_lo + 1);
        for (int px = lo; px < all_lo; ++px)
          for (int j = 0; j < 4; ++j)
            if (std::abs(x + j - px) <= b.radius) {
              add(px, x + j);
              ++cells;
            }
        for (int c = all_lo / kLanes; c <= all_hi / kLanes; ++c) {
          const int px0 = c * kLanes;
          const int l0 = std::max(all_lo - px0, 0), l1 = std::min(all_hi - px0, kLanes - 1);
          // Observer px0 + l's level over column x sits 15 bytes back per lane;
          // over column x + j, j slots (16 bytes each) further on.
          const std::uint8_t* kb = block + b.layout.offset(py, y, c, x - px0 - b.layout.first_dx(px0));
          const std::int32_t* wc = w + px0;
          // The levels for columns x + 16.. : fetch them while these are added.
          __builtin_prefetch(kb + 16 * kLanes);
          __builtin_prefetch(kb + 16 * kLanes - 15 * (kLanes - 1));
          for (int l = l0; l <= l1; ++l) {
            const std::uint8_t* k = kb - 15 * l;
            const std::int32_t wp = wc[l];
            c0[k[0]] += wp;
            c1[k[kLanes]] += wp;
            c2[k[2 * kLanes]] += wp;
            c3[k[3 * kLanes]] += wp;
          }
        }
        for (int px = all_hi + 1; px <= hi; ++px)
          for (int j = 0; j < 4; ++j)
            if (std::abs(x + j - px) <= b.radius) {
              add(px, x + j);
              ++cells;
            }
      }
    }
    for (; x < nx; ++x) {
      const int lo = std::max(0, x - b.radius), hi = std::min(nx - 1, x + b.radius);
      cells += static_cast<std::uint64_t>(hi - lo + 1);
      for (int px = lo; px <= hi; ++px) add(px, x);
    }
  }
  return cells;
}

// Prefix sums up each column of a row's sums (column-major, as in the
// window), converted to F_p in place (float bits in the int32s).
void finish_sums(const Build& b, std::int32_t* sums) {
  const float norm = static_cast<float>(b.weights.norm);
  const std::size_t col_ints = static_cast<std::size_t>(b.geom.nz + 1);
  for (int x = 0; x < b.hf.nx; ++x) {
    std::int32_t* col = sums + static_cast<std::size_t>(x) * col_ints;
    std::int32_t acc = 0;
    for (int k = 0; k < b.geom.nz; ++k) {
      acc += col[k];
      const float f = std::min(1.0f, static_cast<float>(acc) * norm);
      std::memcpy(&col[k], &f, sizeof f);
    }
  }
}

// Copies a finished row into level-major order for the sink.
void transpose_row(const Build& b, const std::int32_t* sums, std::vector<float>& out) {
  const std::size_t col_ints = static_cast<std::size_t>(b.geom.nz + 1);
  const std::size_t nx = static_cast<std::size_t>(b.hf.nx);
  for (std::size_t x = 0; x < nx; ++x) {
    const std::int32_t* col = sums + x * col_ints;
    for (std::size_t k = 0; k < static_cast<std::size_t>(b.geom.nz); ++k) {
      std::memcpy(&out[k * nx + x], &col[k], sizeof(float));
    }
  }
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// How the rows of a build are shared: by rows (a share computes the hulls of
// every observer within range of its band: `bands` null) or by observers
// (its band's observers only; the sums over other shares' rows travel).
struct Split {
  const std::vector<RowBand>* bands = nullptr;
  int index = 0;
  RowExchange* exchange = nullptr;

  bool by_observers() const { return bands != nullptr; }
  // The share whose band holds row y.
  int owner(int y) const {
    for (std::size_t q = 0; q < bands->size(); ++q)
      if (y >= (*bands)[q].first && y < (*bands)[q].end) return static_cast<int>(q);
    return -1;  // validated: the bands cover the grid
  }
  // Every other share with an observer row within `radius` of row y: those
  // that send their sums of row y (their targets are the rows within range of
  // their band). The only rule of who sends what.
  template <class Fn>
  void for_each_source(int y, int radius, Fn&& fn) const {
    for (std::size_t q = 0; q < bands->size(); ++q) {
      const RowBand& o = (*bands)[q];
      if (static_cast<int>(q) != index && o.first < o.end && o.first <= y + radius && o.end - 1 >= y - radius)
        fn(static_cast<int>(q));
    }
  }
};

// A row that another share's observers reach: it waits for their sums
// (split by observers only).
bool needs_other_shares(const Split& split, int radius, int y) {
  bool reached = false;
  if (split.by_observers()) split.for_each_source(y, radius, [&](int) { reached = true; });
  return reached;
}

// Rows of the band waiting for other shares' sums, with this share's, by row.
using HeldRows = std::vector<std::pair<int, std::vector<std::int32_t>>>;

// The rows of the band that waited for other shares' sums, in increasing j:
// theirs added to this share's, then finished and handed to the sink.
Status finish_held_rows(Build& b, const Split& split, HeldRows& held, VolumeRowSink& sink, std::vector<float>& staging,
                        BuildStats& stats) {
  std::vector<std::int32_t> incoming(b.slab_ints);
  for (auto& row : held) {
    const int y = row.first;  // (a structured binding cannot be captured before C++20)
    std::vector<std::int32_t>& sums = row.second;
    const auto t0 = std::chrono::steady_clock::now();
    Status received = Status::ok_status();
    split.for_each_source(y, b.radius, [&](int from) {
      if (!received.ok()) return;
      received = split.exchange->receive(from, y, incoming.data(), incoming.size());
      for (std::size_t n = 0; n < sums.size() && received.ok(); ++n) sums[n] += incoming[n];
    });
    stats.exchange_s += seconds_since(t0);
    VISVOL_RETURN_IF_ERROR(received);
    finish_sums(b, sums.data());
    transpose_row(b, sums.data(), staging);
    VISVOL_RETURN_IF_ERROR(sink.write_row(y, staging.data()));
    std::vector<std::int32_t>().swap(sums);
  }
  const auto t0 = std::chrono::steady_clock::now();
  VISVOL_RETURN_IF_ERROR(split.exchange->finish());
  stats.exchange_s += seconds_since(t0);
  return Status::ok_status();
}

// Target rows [band.first, band.end). Split by rows: the observers within the
// range of them. Split by observers: the band's observers, over the target
// rows within their range. In batches of observer rows; each target row leaves
// the window once no later observer reaches it: to the sink, to the share that
// owns it, or held for the other shares' sums.
Status run_build(Build& b, RowBand band, const Split& split, VolumeRowSink& sink, const ProgressFn& progress,
                 WorkerPool& pool, BuildStats& stats) {
  const int batch = b.plan.batch_rows;
  const int ny = b.hf.ny;
  const bool by_observers = split.by_observers();
  const int obs_lo = by_observers ? band.first : std::max(0, band.first - b.radius);
  const int obs_hi = by_observers ? band.end : std::min(ny, band.end + b.radius);
  const int target_lo = by_observers ? std::max(0, band.first - b.radius) : band.first;
  const int target_hi = by_observers ? std::min(ny, band.end + b.radius) : band.end;
  auto in_band = [&](int y) { return y >= band.first && y < band.end; };
  auto finished_here = [&](int y) { return in_band(y) && !needs_other_shares(split, b.radius, y); };
  const std::size_t ring_floats = static_cast<std::size_t>(ring_size(std::max(b.radius, 1))) * kLanes;
  std::vector<std::vector<float>> ring_a(static_cast<std::size_t>(pool.size()), std::vector<float>(ring_floats));
  std::vector<std::vector<float>> ring_b(static_cast<std::size_t>(pool.size()), std::vector<float>(ring_floats));
  b.cells_per_worker.assign(static_cast<std::size_t>(pool.size()), 0);
  int rows_out = target_lo;  // rows that left the window
  std::vector<std::vector<float>> staging(
      static_cast<std::size_t>(batch),
      std::vector<float>(static_cast<std::size_t>(b.geom.nz) * static_cast<std::size_t>(b.hf.nx)));
  HeldRows held;
  for (int first = obs_lo; first < obs_hi; first += batch) {
    const int rows = std::min(batch, obs_hi - first);
    // phase 1: hull levels of the batch's observers
    auto t0 = std::chrono::steady_clock::now();
    pool.run(rows * b.layout.chunks, [&](int item, int worker) {
      hull_phase(b, first, item, ring_a[static_cast<std::size_t>(worker)], ring_b[static_cast<std::size_t>(worker)]);
    });
    stats.hull_s += seconds_since(t0);
    stats.observer_rows += rows;
    // phase 2: scatter into target rows; finish rows no later observer reaches
    t0 = std::chrono::steady_clock::now();
    const int y_lo = std::max(target_lo, first - b.radius);
    const int y_hi = std::min(target_hi - 1, first + rows - 1 + b.radius);
    const bool last_batch = first + rows == obs_hi;
    const int finished_to = last_batch ? target_hi : std::clamp(first + rows - b.radius, target_lo, target_hi);
    pool.run(y_hi - y_lo + 1, [&](int item, int worker) {
      const int y = y_lo + item;
      b.cells_per_worker[static_cast<std::size_t>(worker)] += scatter_row(b, first, rows, y);
      if (y < finished_to && finished_here(y)) finish_sums(b, b.slab(y));
    });
    // rows done here leave in order, and their slabs are recycled
    while (rows_out < finished_to) {
      // a run of rows that go to the sink: turned to its order in parallel
      int run = 0;
      while (rows_out + run < finished_to && run < batch && finished_here(rows_out + run)) ++run;
      if (run > 0) {
        pool.run(run, [&](int item, int) {
          std::int32_t* slab = b.slab(rows_out + item);
          transpose_row(b, slab, staging[static_cast<std::size_t>(item)]);
          std::fill(slab, slab + b.slab_ints, 0);
        });
        for (int item = 0; item < run; ++item) {
          VISVOL_RETURN_IF_ERROR(sink.write_row(rows_out + item, staging[static_cast<std::size_t>(item)].data()));
        }
        rows_out += run;
        continue;
      }
      std::int32_t* slab = b.slab(rows_out);
      if (!in_band(rows_out)) {
        const int to = split.owner(rows_out);
        VISVOL_RETURN_IF_ERROR(split.exchange->send(to, rows_out, slab, b.slab_ints));
        stats.sent_bytes += b.slab_ints * sizeof(std::int32_t);
      } else {
        held.emplace_back(rows_out, std::vector<std::int32_t>(slab, slab + b.slab_ints));
      }
      std::fill(slab, slab + b.slab_ints, 0);
      ++rows_out;
    }
    stats.scatter_s += seconds_since(t0);
    if (progress) progress(static_cast<double>(first + rows - obs_lo) / (obs_hi - obs_lo));
  }
  if (!by_observers) return Status::ok_status();
  return finish_held_rows(b, split, held, sink, staging.front(), stats);
}

}  // namespace

ObserverWeights observer_weights(const Heightfield& hf, const std::vector<float>& area, const std::vector<float>& w) {
  ObserverWeights out;
  double sum_a = 0, sum_aw = 0;
  for (std::size_t n = 0; n < area.size(); ++n) {
    sum_a += area[n];
    sum_aw += static_cast<double>(area[n]) * (w.empty() ? 1.0 : w[n]);
  }
  // Keep every column's total below 2^30 so int32 sums never overflow, with at
  // most 2^20 counts per unit of weight.
  const double scale = sum_aw > 0 ? std::min(std::ldexp(1.0, 20), std::ldexp(1.0, 30) / sum_aw) : 1.0;
  out.weight.resize(hf.size());
  for (std::size_t n = 0; n < area.size(); ++n) {
    const double aw = static_cast<double>(area[n]) * (w.empty() ? 1.0 : w[n]);
    out.weight[n] = static_cast<std::int32_t>(std::llround(aw * scale));
  }
  out.norm = 1.0 / (scale * sum_a);
  return out;
}

Result<BuildPlan> plan_visibility_build(const Heightfield& hf, const FieldParams& params) {
  VISVOL_RETURN_IF_ERROR(validate(hf, "heightfield"));
  VISVOL_RETURN_IF_ERROR(validate(params, hf));
  BuildPlan plan;
  plan.radius_posts = hull_radius_posts(params, hf);
  plan.table_bytes = HullTable::estimate_bytes(plan.radius_posts, params.exact_rings);
  plan.terrain_bytes = padded_terrain_bytes(hf.nx, hf.ny, plan.radius_posts);
  const LevelRowLayout layout(hf.nx, hf.ny, plan.radius_posts);
  // weight_padded, top_level, eye_m (chunk-padded rows) and the weights a post
  plan.observer_bytes = static_cast<std::size_t>(layout.chunks) * kLanes * static_cast<std::size_t>(hf.ny) * 12 +
                        static_cast<std::size_t>(hf.nx) * static_cast<std::size_t>(hf.ny) * sizeof(std::int32_t);
  const std::size_t per_row = layout.bytes_per_observer_row();
  const std::size_t limit = static_cast<std::size_t>(params.max_memory_mib * kMiB);
  const std::size_t slab =
      static_cast<std::size_t>(params.nz + 1) * static_cast<std::size_t>(hf.nx) * sizeof(std::int32_t);
  auto total_for = [&](int batch) {
    return plan.table_bytes + plan.terrain_bytes + plan.observer_bytes + per_row * static_cast<std::size_t>(batch) +
           window_rows(hf.ny, plan.radius_posts, batch) * slab + staging_for(batch, slab);
  };
  int batch = std::min(kMaxBatchRows, hf.ny);
  while (batch > 1 && total_for(batch) > limit) --batch;
  plan.batch_rows = batch;
  plan.level_bytes = per_row * static_cast<std::size_t>(batch);
  plan.window_bytes = window_rows(hf.ny, plan.radius_posts, batch) * slab;
  plan.staging_bytes = staging_for(batch, slab);
  if (plan.total_bytes() > limit) {
    std::ostringstream msg;
    // in MiB to a hundredth (a small build needs less than one)
    auto mib = [](std::size_t bytes) { return static_cast<double>(bytes) / static_cast<double>(kMiB); };
    msg << std::fixed << std::setprecision(2) << "field build for " << hf.nx << " x " << hf.ny << " x " << params.nz
        << " voxels with hull radius " << plan.radius_posts << " posts needs " << mib(plan.total_bytes())
        << " MiB of working memory (hull levels " << mib(plan.level_bytes) << ", histogram window "
        << mib(plan.window_bytes) << ", finished rows " << mib(plan.staging_bytes) << ", table "
        << mib(plan.table_bytes) << ", terrain " << mib(plan.terrain_bytes) << ", observers "
        << mib(plan.observer_bytes) << "); the limit is " << std::defaultfloat << std::setprecision(6)
        << params.max_memory_mib << " MiB: use a smaller range, fewer levels or a smaller grid";
    return resource_error(msg.str());
  }
  return plan;
}

Status build_visibility(const Heightfield& hf, const FieldParams& params, VolumeRowSink& sink,
                        const ProgressFn& progress, BuildStats* stats) {
  return build_visibility_rows(hf, params, RowBand{0, hf.ny}, sink, progress, stats);
}

namespace {

Status build_band(const Heightfield& hf, const FieldParams& params, RowBand band, const Split& split,
                  VolumeRowSink& sink, const ProgressFn& progress, BuildStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  Result<BuildPlan> plan = plan_visibility_build(hf, params);
  if (!plan.ok()) return plan.status();
  try {
    Build b(hf, params, *plan);
    prepare_observers(b);
    b.hull_levels.assign(plan->level_bytes, static_cast<std::uint8_t>(b.geom.nz));
    b.window.assign(static_cast<std::size_t>(b.win) * b.slab_ints, 0);
    WorkerPool pool(params.threads);
    BuildStats local;
    VISVOL_RETURN_IF_ERROR(run_build(b, band, split, sink, progress, pool, local));
    if (stats) {
      *stats = local;
      stats->wall_s = seconds_since(t0);
      stats->threads = pool.size();
      stats->plan = *plan;
      stats->hull_cells = 0;
      for (std::uint64_t c : b.cells_per_worker) stats->hull_cells += c;
    }
  } catch (const std::bad_alloc&) {
    return resource_error("field build: out of memory allocating " + std::to_string(plan->total_bytes() / kMiB) +
                          " MiB of working memory");
  }
  return Status::ok_status();
}

}  // namespace

Status build_visibility_rows(const Heightfield& hf, const FieldParams& params, RowBand band, VolumeRowSink& sink,
                             const ProgressFn& progress, BuildStats* stats) {
  if (band.first < 0 || band.end > hf.ny || band.first >= band.end) {
    return invalid_argument("field build: rows " + std::to_string(band.first) + ".." + std::to_string(band.end) +
                            " are not a band of the grid's " + std::to_string(hf.ny));
  }
  return build_band(hf, params, band, Split{}, sink, progress, stats);
}

Status build_visibility_share(const Heightfield& hf, const FieldParams& params, const std::vector<RowBand>& bands,
                              int index, RowExchange& exchange, VolumeRowSink& sink, const ProgressFn& progress,
                              BuildStats* stats) {
  int next = 0;  // the bands must cover rows 0..ny in order
  bool in_order = !bands.empty();
  for (const RowBand& band : bands) {
    in_order = in_order && band.first == next && band.end >= band.first;
    next = band.end;
  }
  if (!in_order || next != hf.ny) {
    return invalid_argument("field build: the " + std::to_string(bands.size()) +
                            " bands of the split do not cover the grid's " + std::to_string(hf.ny) + " rows in order");
  }
  if (index < 0 || index >= static_cast<int>(bands.size())) {
    return invalid_argument("field build: share " + std::to_string(index) + " is not one of the split's " +
                            std::to_string(bands.size()));
  }
  const RowBand band = bands[static_cast<std::size_t>(index)];
  if (band.first == band.end) {  // no observers, no rows: nothing to send or wait for
    if (stats) *stats = BuildStats{};
    return Status::ok_status();
  }
  return build_band(hf, params, band, Split{&bands, index, &exchange}, sink, progress, stats);
}

namespace {
class DenseSink final : public VolumeRowSink {
 public:
  explicit DenseSink(DenseVolume& v) : v_(v) {}
  Status write_row(int j, const float* values) override {
    const VolumeGeometry& g = v_.geometry;
    for (int k = 0; k < g.nz; ++k) {
      std::memcpy(&v_.values[g.index(0, j, k)], values + static_cast<std::size_t>(k) * static_cast<std::size_t>(g.nx),
                  static_cast<std::size_t>(g.nx) * sizeof(float));
    }
    return Status::ok_status();
  }

 private:
  DenseVolume& v_;
};
}  // namespace

Result<DenseVolume> build_visibility_dense(const Heightfield& hf, const FieldParams& params, const ProgressFn& progress,
                                           BuildStats* stats) {
  VISVOL_RETURN_IF_ERROR(validate(hf, "heightfield"));
  VISVOL_RETURN_IF_ERROR(validate(params, hf));
  DenseVolume v;
  v.geometry = volume_geometry(hf, params);
  const double bytes = static_cast<double>(v.geometry.voxel_count()) * sizeof(float);
  if (bytes > params.max_memory_mib * kMiB) {
    return resource_error("field of " + std::to_string(v.geometry.voxel_count()) + " voxels needs " +
                          std::to_string(static_cast<long long>(bytes / kMiB)) +
                          " MiB in memory, over the limit; stream it to a pack instead");
  }
  try {
    v.values.assign(v.geometry.voxel_count(), 0.0f);
  } catch (const std::bad_alloc&) {
    return resource_error("out of memory allocating the field");
  }
  DenseSink sink(v);
  VISVOL_RETURN_IF_ERROR(build_visibility(hf, params, sink, progress, stats));
  return v;
}

}  // namespace visvol::fields
