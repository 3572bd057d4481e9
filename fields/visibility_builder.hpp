// The visibility field F_p (paper, section 3) by visibility hulls.
//
//   F_p(Q) = sum over posts P of S_P(Q) A(P) W(P) / sum over posts of A(P)
//
// Visibility is symmetric, so voxel Q above column c sees observer P exactly
// when Q lies above P's hull over c. Each observer's hull level over each target
// column is computed once (phase 1, vectorised over kLanes neighbouring
// observers), then scattered as +A*W at that level (and -A*W where the range
// ends) into per-row histograms and prefix-summed up each column (phase 2).
//
// Results are identical whatever the thread count: weights are fixed-point
// integers, so the sums do not depend on their order.
//
// Memory: a rolling window of 2r+B target rows of (nz+1) x nx int32 plus the
// hull levels of B observer rows; finished rows stream to a sink, so a field
// larger than memory can be written tile by tile.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "base/status.hpp"
#include "fields/field_params.hpp"
#include "fields/heightfield.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// Receives finished rows of the field, each once, from one thread: in
// increasing j, but for a build split by observers, whose rows within range of
// another share's band come last (build_visibility_share).
class VolumeRowSink {
 public:
  virtual ~VolumeRowSink() = default;
  // Row j: nz * nx values of F_p in [0, 1], level-major (values[k * nx + i]).
  virtual Status write_row(int j, const float* values) = 0;
};

struct BuildPlan {
  int radius_posts = 0;  // hull radius actually used
  int batch_rows = 0;    // observer rows per batch
  std::size_t table_bytes = 0;
  std::size_t terrain_bytes = 0;
  std::size_t level_bytes = 0;     // hull levels of one batch
  std::size_t window_bytes = 0;    // rolling histogram window
  std::size_t staging_bytes = 0;   // finished rows of one batch, in the sink's order
  std::size_t observer_bytes = 0;  // per observer: weight, eye, range top (chunk-padded rows), and its weight
  std::size_t total_bytes() const {
    return table_bytes + terrain_bytes + level_bytes + window_bytes + staging_bytes + observer_bytes;
  }
};

// Sizes the working memory of a build; refuses (Errc::resource) when it would
// exceed params.max_memory_mib, naming the sizes.
Result<BuildPlan> plan_visibility_build(const Heightfield& hf, const FieldParams& params);

struct BuildStats {
  double wall_s = 0;
  double hull_s = 0;     // phase 1: hull levels
  double scatter_s = 0;  // phase 2: scatter, prefix sums, hand-off
  // A build split by observers (build_visibility_share): waiting for and
  // adding the other shares' partial sums, and the bytes of those sent.
  double exchange_s = 0;
  std::uint64_t sent_bytes = 0;
  int observer_rows = 0;  // rows of observers whose hulls were computed
  int threads = 0;
  BuildPlan plan;
  std::uint64_t hull_cells = 0;  // (observer, target column) pairs evaluated
  double cells_per_s_per_core() const {
    return wall_s > 0 && threads > 0 ? static_cast<double>(hull_cells) / wall_s / threads : 0;
  }
};

// Called from the building thread with the fraction of rows done.
using ProgressFn = std::function<void(double fraction)>;

// Builds F_p for one level of detail, streaming rows to `sink`.
Status build_visibility(const Heightfield& hf, const FieldParams& params, VolumeRowSink& sink,
                        const ProgressFn& progress = {}, BuildStats* stats = nullptr);

// Target rows [first, end) of the grid.
struct RowBand {
  int first = 0, end = 0;
};

// Builds rows [band.first, band.end) of F_p only, streaming them to `sink`:
// each exactly the whole build's row (the observers within the range of the
// band are all counted; the sums are integers). What one of several
// processes builds; its cost is that of the band's observers and those of
// the range around it.
Status build_visibility_rows(const Heightfield& hf, const FieldParams& params, RowBand band, VolumeRowSink& sink,
                             const ProgressFn& progress = {}, BuildStats* stats = nullptr);

// The transport between the shares of a build split by observers: the
// partial sums of one target row (nx * (nz + 1) int32 values), exact. A row
// travels once from each share whose observers reach it to the share that
// owns it. Called from the building thread only.
class RowExchange {
 public:
  virtual ~RowExchange() = default;
  // Row j's partial sums for share `to`; returns without waiting for `to`
  // (the values are copied or sent before it returns).
  virtual Status send(int to, int j, const std::int32_t* sums, std::size_t count) = 0;
  // Share `from`'s partial sums of row j into `sums`; waits for them.
  virtual Status receive(int from, int j, std::int32_t* sums, std::size_t count) = 0;
  // Waits until every row this share sent has left.
  virtual Status finish() = 0;
};

// Rows [band.first, band.end) of F_p, computed from the observers of the
// band only: `bands` partition the grid's rows in order (empty bands
// allowed), one per share, and this is share `index`. Each observer's hull
// is computed once in the whole build (build_visibility_rows computes those
// within range of a band again in every band that they reach); the sums
// over the target rows within range of another share's observers travel
// through `exchange`, as integers, so every row is the whole build's, byte for
// byte. Every share runs this at once with the same `bands` (a share's rows
// near its band's edges wait for its neighbours' sums). The sink gets
// rows in increasing j, but for those within range of another share's
// observers, which come last.
Status build_visibility_share(const Heightfield& hf, const FieldParams& params, const std::vector<RowBand>& bands,
                              int index, RowExchange& exchange, VolumeRowSink& sink, const ProgressFn& progress = {},
                              BuildStats* stats = nullptr);

// Builds F_p into memory.
Result<DenseVolume> build_visibility_dense(const Heightfield& hf, const FieldParams& params,
                                           const ProgressFn& progress = {}, BuildStats* stats = nullptr);

// Fixed-point observer weights: round(A * W * scale). F_p = count * norm.
struct ObserverWeights {
  std::vector<std::int32_t> weight;  // per post
  double norm = 0;                   // 1 / (scale * sum of A)
};
ObserverWeights observer_weights(const Heightfield& hf, const std::vector<float>& area, const std::vector<float>& w);

}  // namespace visvol::fields
