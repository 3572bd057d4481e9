// Visibility hulls: the horizon seen from one observer post, ring by ring.
//
// The terrain model is the one of the exact R3 sight line (Franklin & Ray): a
// sight line from observer P' to target Q is tested wherever it crosses a grid
// line, with the terrain interpolated linearly along that grid line. For a target
// c in Chebyshev ring m, the sight line crosses ring m-1's grid line between two
// posts a and b, and at most one grid line of the other direction between rings
// m-1 and m. The horizon slope H(c) = the largest (terrain - eye) / distance over
// all crossings is therefore
//   H(c) = max(lerp(H(a), H(b)), slope at the ring m-1 crossing,
//              slope at the other crossing),
// exact for the two nearest crossings and interpolated for the farther ones
// (the paper's Algorithm 1 and Franklin's XDraw, with R3's crossings). The lowest
// visible height over c is eye + |Pc| * H(c) (plus the curvature drop at c).
//
// Everything that depends only on the offset c - P (stencil, weights, distances,
// curvature drops) is precomputed in a HullTable shared by all observers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "fields/field_params.hpp"
#include "fields/heightfield.hpp"

namespace visvol::fields {

// Observers processed together by the vectorised kernel (one SIMD register of
// floats on AVX-512; two on AVX2).
inline constexpr int kLanes = 16;
// Hull levels are stored as bytes; level nz means "never visible".
inline constexpr int kMaxHeightLevels = 255;
// Horizon slope before any crossing (rings 0 and 1 see everything).
inline constexpr float kNoHorizon = -1.0e30f;

// One target cell of a ring, relative to the observer.
struct HullEntry {
  std::uint16_t a = 0, b = 0;   // stencil cells, as indices into the previous ring (kMaxHullRing)
  std::int16_t dx = 0, dy = 0;  // offset from the observer, posts
  float t = 0;                  // weight of b (and of post tb) at the ring m-1 crossing
  std::int32_t ta = 0, tb = 0;  // terrain offsets of the ring m-1 crossing's posts
  float inv_d1 = 0;             // 1 / distance to the ring m-1 crossing, 1/m
  float drop1_m = 0;            // curvature drop at the ring m-1 crossing
  std::int32_t tc = 0, td = 0;  // terrain offsets of the other crossing's posts
  float t2 = 0;                 // weight of td
  float inv_d2 = 0;             // 1 / distance to the other crossing, 1/m
  float drop2_m = 0;
  float d_m = 0;           // distance to the target, m
  float drop_m = 0;        // curvature drop at the target
  float span_m = 0;        // sphere range: half height of the range here (<0: outside)
  std::int32_t t_own = 0;  // terrain offset of the target's own post (dy * stride + dx)
};

// One grid-line crossing of a sight line: terrain interpolated between two
// posts of the crossed line.
struct Crossing {
  std::int32_t ta = 0, tb = 0;  // terrain offsets of the two posts
  float t = 0;                  // weight of tb
  float inv_d = 0;              // 1 / distance from the observer, 1/m
  float drop_m = 0;             // curvature drop at the crossing
};

// Appends every crossing of the open sight line from the observer to offset
// (dx, dy): R3's exact set.
void append_crossings(int dx, int dy, double spacing_m, double curvature_coeff, int stride, std::vector<Crossing>& out);

// The farthest ring a horizon reaches: a ring's indices (8 m of them) fit the
// 16-bit stencil indices of HullEntry.
inline constexpr int kMaxHullRing = 8191;

// Index of cell (dx, dy) within Chebyshev ring m (m >= 1): the top row left to
// right, then the left and right cells of each middle row, then the bottom row.
int ring_index(int dx, int dy, int m);
inline int ring_size(int m) { return m == 0 ? 1 : 8 * m; }

// Offsets from an observer: dx in dx_lo..dx_hi, dy in dy_lo..dy_hi.
struct OffsetBox {
  int dx_lo = std::numeric_limits<int>::min(), dx_hi = std::numeric_limits<int>::max();
  int dy_lo = std::numeric_limits<int>::min(), dy_hi = std::numeric_limits<int>::max();
  bool contains(int dx, int dy) const { return dx >= dx_lo && dx <= dx_hi && dy >= dy_lo && dy <= dy_hi; }
};

// Appends the entries of ring m (m >= 2) in ring_index order. Terrain offsets
// are flat indices for a terrain stored with row stride `stride`. Only the
// entries inside `box` are filled; the others keep HullEntry{} (d_m 0).
void append_ring_entries(int m, double spacing_m, double curvature_coeff, RangeShape shape, double range_m, int stride,
                         std::vector<HullEntry>& out, const OffsetBox& box = {});

// All rings 2..radius, stored for reuse by every observer. Rings up to
// exact_rings are evaluated exactly (every crossing; that is where neighbouring
// sight lines diverge most and interpolation errs most); farther rings use the
// stencil.
class HullTable {
 public:
  HullTable(int radius, int exact_rings, double spacing_m, double curvature_coeff, RangeShape shape, double range_m,
            int stride);
  int radius() const { return radius_; }
  int exact_rings() const { return exact_rings_; }
  // Crossings of entry n of ring m (m <= exact_rings).
  const Crossing* crossings_begin(int m, int n) const {
    return crossings_.data() + crossing_start_[ring_start_[static_cast<std::size_t>(m)] + static_cast<std::size_t>(n)];
  }
  const Crossing* crossings_end(int m, int n) const {
    return crossings_.data() +
           crossing_start_[ring_start_[static_cast<std::size_t>(m)] + static_cast<std::size_t>(n) + 1];
  }
  const HullEntry* ring(int m) const { return entries_.data() + ring_start_[static_cast<std::size_t>(m)]; }
  // Rings 0 and 1 (only offsets, distances and spans are meaningful).
  const std::array<HullEntry, 9>& inner() const { return inner_; }
  std::size_t entry_count() const { return entries_.size(); }
  std::size_t bytes() const { return entries_.size() * sizeof(HullEntry) + crossings_.size() * sizeof(Crossing); }
  // Rough size before building, for memory plans.
  static std::size_t estimate_bytes(int radius, int exact_rings);

 private:
  int radius_;
  int exact_rings_;
  std::vector<Crossing> crossings_;
  std::vector<std::size_t> crossing_start_;  // per entry of the exact rings, plus one
  std::vector<HullEntry> entries_;
  std::vector<std::size_t> ring_start_;
  std::array<HullEntry, 9> inner_{};
};

// Terrain padded on every side so that a table's offsets never leave the array.
// Padding posts are far below the terrain and never block a sight line.
struct PaddedTerrain {
  int nx = 0, ny = 0, pad = 0, stride = 0;
  std::vector<float> height_m;
  // First level at or above the terrain per post, nz in the padding.
  std::vector<std::int32_t> ground_level;

  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j + pad) * static_cast<std::size_t>(stride) + static_cast<std::size_t>(i + pad);
  }
};
PaddedTerrain pad_terrain(const Heightfield& hf, const VolumeGeometry& g, int radius);
std::size_t padded_terrain_bytes(int nx, int ny, int radius);

// Where the hull levels of one observer row go: for each chunk of kLanes
// observers, target row and offset slot, kLanes bytes. Only targets inside the grid
// have a place.
struct LevelRowLayout {
  int nx = 0, ny = 0, radius = 0, chunks = 0;
  int rows = 0;   // target rows per observer row
  int slots = 0;  // target offsets per chunk

  LevelRowLayout() = default;
  LevelRowLayout(int nx_, int ny_, int radius_);
  int first_row(int py) const { return py - radius > 0 ? py - radius : 0; }
  int last_row(int py) const { return py + radius < ny - 1 ? py + radius : ny - 1; }
  int first_dx(int px0) const {
    const int lo = -(px0 + kLanes - 1);
    return lo > -radius ? lo : -radius;
  }
  int last_dx(int px0) const { return radius < nx - 1 - px0 ? radius : nx - 1 - px0; }
  std::size_t bytes_per_observer_row() const {
    return static_cast<std::size_t>(rows) * static_cast<std::size_t>(chunks) * static_cast<std::size_t>(slots) * kLanes;
  }
  // Offset of (target row y, chunk, slot) within one observer row's block.
  // Chunk-major, so that one chunk's levels are one contiguous block while the
  // kernel writes them.
  std::size_t offset(int py, int y, int chunk, int slot) const {
    return ((static_cast<std::size_t>(chunk) * static_cast<std::size_t>(rows) +
             static_cast<std::size_t>(y - first_row(py))) *
                static_cast<std::size_t>(slots) +
            static_cast<std::size_t>(slot)) *
           kLanes;
  }
};

// How heights map to levels.
struct LevelMap {
  float z0_m = 0;
  float inv_dz = 1;  // 1 / level spacing, 1/m
  int nz = 0;
};

// One chunk of kLanes observers on row py starting at column px0.
struct ObserverChunk {
  int px0 = 0, py = 0;
  float eye_m[kLanes] = {};               // eye heights (lanes past the grid: any value)
  std::int32_t floor_level[kLanes] = {};  // lowest level each observer's range admits
};

// Phase 1 of the field: for every target of the chunk's observers, the first
// level from which each observer is visible (clamped to 0..nz), written to
// `out` (one observer row's block of `layout`). Only the bytes of an observer
// and a target both inside the grid are meaningful; of the others some are
// written with values of no use, some left as they were. Scratch: two ring
// buffers of 8 * radius * kLanes floats. Cost: O(entries * kLanes); no
// allocation. Preconditions, on which the levels' range 0..nz rests (the
// scatter indexes with them): levels.nz <= kMaxHeightLevels, the terrain's
// ground levels made by pad_terrain with the same nz, every floor_level in
// 0..nz.
void hull_levels_chunk(const HullTable& table, const PaddedTerrain& terrain, const LevelRowLayout& layout,
                       const LevelMap& levels, RangeShape shape, const ObserverChunk& chunk, float* ring_a,
                       float* ring_b, std::uint8_t* out);

// The vector width hull_levels_chunk runs at on this CPU (16 lanes with
// AVX-512, 8 with AVX2, 4 otherwise; 16 in the sanitizer builds).
int hull_kernel_width();
// The build of the kernel at `width` lanes, where this build and CPU have
// it (an AVX-512 CPU runs the AVX2 and baseline builds too): false, and
// nothing written, where not. Tests hold every width to the same bytes.
bool hull_levels_chunk_at_width(int width, const HullTable& table, const PaddedTerrain& terrain,
                                const LevelRowLayout& layout, const LevelMap& levels, RangeShape shape,
                                const ObserverChunk& chunk, float* ring_a, float* ring_b, std::uint8_t* out);

// The horizon slope H of every target around one observer (scalar; for
// viewsheds, point hulls and tests), by the same rules as the kernel.
// `horizon` receives (2r+1)^2 values indexed (dy + r) * (2r + 1) + (dx + r);
// rings 0 and 1 get kNoHorizon. With `grid_only`, only the targets on the
// terrain's grid are computed (the others get kNoHorizon): a grid target's
// horizon depends on grid targets only (its sight line stays on the grid, and
// the posts either side of it where it crosses a ring are grid posts), so
// those values are the same, at the cost of the grid's posts rather than the
// (2r+1)^2 square's. The terrain then needs a padding of one post only
// (pad_terrain(hf, g, 2) gives kLanes + 4), not the radius.
void observer_horizon(const PaddedTerrain& terrain, int radius, int exact_rings, double spacing_m,
                      double curvature_coeff, int pi, int pj, double eye_z_m, std::vector<float>& horizon,
                      bool grid_only = false);

}  // namespace visvol::fields
