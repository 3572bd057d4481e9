#include "fields/hull_kernel.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include "fields/simd.hpp"

namespace visvol::fields {

namespace {

// Padding heights sit this far below the lowest post: they never block.
constexpr float kPaddingDepthM = 1.0e6f;
// Span of a sphere range outside the sphere: puts both bounds beyond the grid.
constexpr float kOutsideSpan = -1.0e30f;

double curvature_drop_m(double coeff, double d_m) { return coeff * d_m * d_m / (2.0 * kEarthRadiusM); }

// Vertical half extent of a sphere of radius range_m at horizontal distance d_m:
// kOutsideSpan outside (so every level test fails), unused by other shapes.
float sphere_span_m(RangeShape shape, double range_m, double d_m) {
  if (shape != RangeShape::sphere) return std::numeric_limits<float>::max();
  if (d_m > range_m) return kOutsideSpan;
  return static_cast<float>(std::sqrt(range_m * range_m - d_m * d_m));
}

}  // namespace

int ring_index(int dx, int dy, int m) {
  if (dy == -m) return dx + m;
  if (dy == m) return (2 * m + 1) + 2 * (2 * m - 1) + (dx + m);
  return 2 * m + 1 + 2 * (dy + m - 1) + (dx == -m ? 0 : 1);
}

void append_ring_entries(int m, double spacing_m, double curvature_coeff, RangeShape shape, double range_m, int stride,
                         std::vector<HullEntry>& out, const OffsetBox& box) {
  const std::size_t first = out.size();
  out.resize(first + static_cast<std::size_t>(ring_size(m)));
  // the ring's cells only: the top and bottom rows, then the two sides
  auto cell = [&](int dx, int dy) {
    if (!box.contains(dx, dy)) return;
    HullEntry e;
    e.dx = static_cast<std::int16_t>(dx);
    e.dy = static_cast<std::int16_t>(dy);
    const double d_posts = std::hypot(static_cast<double>(dx), static_cast<double>(dy));
    const double d = d_posts * spacing_m;
    e.d_m = static_cast<float>(d);
    e.drop_m = static_cast<float>(curvature_drop_m(curvature_coeff, d));
    e.span_m = sphere_span_m(shape, range_m, d);
    e.t_own = static_cast<std::int32_t>(dy * stride + dx);

    // Work in (major, minor) axes: the major axis is the one where |offset| = m.
    const bool x_major = std::abs(dx) == m;
    const int major_sign = x_major ? (dx > 0 ? 1 : -1) : (dy > 0 ? 1 : -1);
    const double minor = x_major ? dy : dx;
    auto to_dxdy = [&](int major, int minor_posts, int& ox, int& oy) {
      ox = x_major ? major : minor_posts;
      oy = x_major ? minor_posts : major;
    };
    auto terrain_offset = [&](int major, int minor_posts) {
      int ox = 0, oy = 0;
      to_dxdy(major, minor_posts, ox, oy);
      return static_cast<std::int32_t>(oy * stride + ox);
    };
    auto prev_index = [&](int major, int minor_posts) {
      int ox = 0, oy = 0;
      to_dxdy(major, minor_posts, ox, oy);
      return static_cast<std::uint16_t>(ring_index(ox, oy, m - 1));
    };

    // Crossing of ring m-1's grid line (major = +-(m-1)).
    const int major_prev = major_sign * (m - 1);
    const double minor_at_prev = minor * (m - 1) / m;
    const double lo = std::floor(minor_at_prev);
    const double t = minor_at_prev - lo;
    const int i0 = static_cast<int>(lo);
    const int i1 = t > 0 ? i0 + 1 : i0;
    e.a = prev_index(major_prev, i0);
    e.b = prev_index(major_prev, i1);
    e.t = static_cast<float>(t);
    e.ta = terrain_offset(major_prev, i0);
    e.tb = terrain_offset(major_prev, i1);
    const double d1 = d * (m - 1) / m;
    e.inv_d1 = static_cast<float>(1.0 / d1);
    e.drop1_m = static_cast<float>(curvature_drop_m(curvature_coeff, d1));

    // A grid line of the minor axis strictly between ring m-1 and ring m: the
    // sight line's minor coordinate passes an integer k there.
    const double seg_lo = std::min(minor_at_prev, minor);
    const double seg_hi = std::max(minor_at_prev, minor);
    double k = std::ceil(seg_hi) - 1.0;
    if (k > seg_lo && k < seg_hi) {
      const double major_abs = m * k / minor;  // |major coordinate| at minor = k
      const double f = std::floor(major_abs);
      const int kk = static_cast<int>(k);
      e.tc = terrain_offset(major_sign * static_cast<int>(f), kk);
      e.td = terrain_offset(major_sign * (static_cast<int>(f) + 1), kk);
      e.t2 = static_cast<float>(major_abs - f);
      const double d2 = d * k / minor;
      e.inv_d2 = static_cast<float>(1.0 / d2);
      e.drop2_m = static_cast<float>(curvature_drop_m(curvature_coeff, d2));
    } else {
      // No second crossing: repeat the first (max() makes it harmless).
      e.tc = e.ta;
      e.td = e.tb;
      e.t2 = e.t;
      e.inv_d2 = e.inv_d1;
      e.drop2_m = e.drop1_m;
    }
    out[first + static_cast<std::size_t>(ring_index(dx, dy, m))] = e;
  };
  for (int dx = -m; dx <= m; ++dx) {
    cell(dx, -m);
    cell(dx, m);
  }
  for (int dy = -m + 1; dy <= m - 1; ++dy) {
    cell(-m, dy);
    cell(m, dy);
  }
}

HullTable::HullTable(int radius, int exact_rings, double spacing_m, double curvature_coeff, RangeShape shape,
                     double range_m, int stride)
    : radius_(radius), exact_rings_(std::min(exact_rings, radius)) {
  const std::size_t side = 2 * static_cast<std::size_t>(radius) + 1;
  entries_.reserve(side * side);
  ring_start_.assign(static_cast<std::size_t>(radius) + 2, 0);
  for (int m = 2; m <= radius; ++m) {
    ring_start_[static_cast<std::size_t>(m)] = entries_.size();
    append_ring_entries(m, spacing_m, curvature_coeff, shape, range_m, stride, entries_);
    if (m > exact_rings_) continue;
    for (std::size_t n = ring_start_[static_cast<std::size_t>(m)]; n < entries_.size(); ++n) {
      crossing_start_.push_back(crossings_.size());
      append_crossings(entries_[n].dx, entries_[n].dy, spacing_m, curvature_coeff, stride, crossings_);
    }
  }
  crossing_start_.push_back(crossings_.size());
  ring_start_[static_cast<std::size_t>(radius) + 1] = entries_.size();
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      HullEntry e;
      e.dx = static_cast<std::int16_t>(dx);
      e.dy = static_cast<std::int16_t>(dy);
      const double d = std::hypot(static_cast<double>(dx), static_cast<double>(dy)) * spacing_m;
      e.d_m = static_cast<float>(d);
      e.drop_m = static_cast<float>(curvature_drop_m(curvature_coeff, d));
      e.span_m = sphere_span_m(shape, range_m, d);
      e.t_own = static_cast<std::int32_t>(dy * stride + dx);
      inner_[static_cast<std::size_t>((dy + 1) * 3 + dx + 1)] = e;
    }
  }
}

std::size_t HullTable::estimate_bytes(int radius, int exact_rings) {
  const std::size_t side = 2 * static_cast<std::size_t>(radius) + 1;
  const std::size_t m = static_cast<std::size_t>(std::min(radius, exact_rings));
  // About 8m cells of up to 2m crossings per exact ring.
  return side * side * sizeof(HullEntry) + 16 * m * m * m / 3 * sizeof(Crossing);
}

void append_crossings(int dx, int dy, double spacing_m, double curvature_coeff, int stride,
                      std::vector<Crossing>& out) {
  const double d_total = std::hypot(double(dx), double(dy)) * spacing_m;
  // Lines x = k (vertical_line) or y = k strictly between the observer and target.
  auto add_lines = [&](bool vertical_line) {
    const int main_offset = vertical_line ? dx : dy;
    const int other_offset = vertical_line ? dy : dx;
    const int step = main_offset > 0 ? 1 : -1;
    for (int k = step; k != main_offset && main_offset != 0; k += step) {
      const double f = double(k) / main_offset;
      const double along = f * other_offset;
      const double lo = std::floor(along);
      Crossing c;
      const int a = static_cast<int>(lo);
      const int b = along > lo ? a + 1 : a;
      c.ta = vertical_line ? a * stride + k : k * stride + a;
      c.tb = vertical_line ? b * stride + k : k * stride + b;
      c.t = static_cast<float>(along - lo);
      const double d = f * d_total;
      c.inv_d = static_cast<float>(1.0 / d);
      c.drop_m = static_cast<float>(curvature_drop_m(curvature_coeff, d));
      out.push_back(c);
    }
  };
  add_lines(true);
  add_lines(false);
}

PaddedTerrain pad_terrain(const Heightfield& hf, const VolumeGeometry& g, int radius) {
  PaddedTerrain t;
  t.nx = hf.nx;
  t.ny = hf.ny;
  t.pad = radius + kLanes + 2;
  t.stride = hf.nx + 2 * t.pad;
  const std::size_t rows = static_cast<std::size_t>(hf.ny) + 2 * static_cast<std::size_t>(t.pad);
  const float low = height_range(hf).min_m - kPaddingDepthM;
  t.height_m.assign(rows * static_cast<std::size_t>(t.stride), low);
  t.ground_level.assign(rows * static_cast<std::size_t>(t.stride), g.nz);
  for (int j = 0; j < hf.ny; ++j) {
    for (int i = 0; i < hf.nx; ++i) {
      const double h = hf.at(i, j);
      t.height_m[t.index(i, j)] = hf.at(i, j);
      const double level = std::ceil((h - g.z0_m) / g.dz_m);
      t.ground_level[t.index(i, j)] = static_cast<std::int32_t>(std::clamp(level, 0.0, static_cast<double>(g.nz)));
    }
  }
  return t;
}

std::size_t padded_terrain_bytes(int nx, int ny, int radius) {
  const std::size_t pad = static_cast<std::size_t>(radius) + kLanes + 2;
  return (static_cast<std::size_t>(nx) + 2 * pad) * (static_cast<std::size_t>(ny) + 2 * pad) *
         (sizeof(float) + sizeof(std::int32_t));
}

LevelRowLayout::LevelRowLayout(int nx_, int ny_, int radius_) : nx(nx_), ny(ny_), radius(radius_) {
  chunks = (nx + kLanes - 1) / kLanes;
  rows = std::min(2 * radius + 1, ny);
  slots = std::min(2 * radius + 1, nx + kLanes - 1);
}

namespace {

// The kernel runs the chunk's kLanes observers in passes of W lanes, W the
// widest vector the CPU computes natively: 16 floats on AVX-512, 8 on AVX2,
// 4 on the baseline's SSE. (GCC 12 lowers a comparison of 16 floats lane by
// lane, in scalar code, on a target without 512-bit registers, and keeps
// such vectors on the stack: on AVX2 the kernel ran at 79 M hull cells per
// second and core, against 657 on AVX-512.) The lanes are independent
// observers, so a pass reads and writes its own W of every kLanes-wide slot.
using simd::Lanes;

template <class V, class T>
VISVOL_SIMD_INLINE void load(V& v, const T* p) {
  simd::load_unaligned(v, p);
}
template <class V>
VISVOL_SIMD_INLINE void max_into(V& a, const V& b) {
  a = a > b ? a : b;
}

// floor(q) for q >= -4 (truncation of a positive number is its floor).
template <int W>
VISVOL_SIMD_INLINE void floor_into(typename Lanes<W>::I& out, const typename Lanes<W>::F& q) {
  out = __builtin_convertvector(q + 4.0f, typename Lanes<W>::I) - 4;
}

// (z - z0) / dz clamped to [-2, hi].
template <int W>
VISVOL_SIMD_INLINE void level_coordinate(typename Lanes<W>::F& q, const typename Lanes<W>::F& z_m, const LevelMap& lv,
                                         float hi) {
  using F = typename Lanes<W>::F;
  q = (z_m - lv.z0_m) * lv.inv_dz;
  // written as max and min (one instruction each): q is never NaN
  const F lo_q = F{} - 2.0f, hi_q = F{} + hi;
  q = q > lo_q ? q : lo_q;
  q = q < hi_q ? q : hi_q;
}

// First level strictly above each hull height (visibility needs z > hull).
template <int W>
VISVOL_SIMD_INLINE void level_above(typename Lanes<W>::I& out, const typename Lanes<W>::F& hull_m, const LevelMap& lv) {
  typename Lanes<W>::F q;
  level_coordinate<W>(q, hull_m, lv, static_cast<float>(lv.nz - 1));
  floor_into<W>(out, q);
  out += 1;
}

// First level at or above a height (for the sphere's lower bound):
// ceil(q) = floor(q) + (floor(q) < q); comparisons give -1 for true.
template <int W>
VISVOL_SIMD_INLINE void level_at_or_above(typename Lanes<W>::I& out, const typename Lanes<W>::F& z_m,
                                          const LevelMap& lv) {
  typename Lanes<W>::F q;
  level_coordinate<W>(q, z_m, lv, static_cast<float>(lv.nz));
  floor_into<W>(out, q);
  out -= __builtin_convertvector(out, typename Lanes<W>::F) < q;
}

// Levels are 0..nz <= 255 by construction (every bound above is clamped to
// nz, and so are the ground and floor levels: hull_levels_chunk's
// preconditions), so a byte holds each. The 16 bytes of a 16-lane pass are
// narrowed in a register and stored whole: narrowing straight to memory
// (vpmovdb to memory on AVX-512) is slow.
#if defined(VISVOL_SIMD_DISPATCH) && __GNUC__ >= 12
#define VISVOL_SHUFFLE_LEVELS_8 1
// GCC 12 narrows 8 lanes for AVX2 lane by lane in scalar code; a shuffle
// picking the low byte of each lane (little-endian; the narrowing wraps
// modulo 256 too) gives the same bytes in four vector instructions. Only
// GCC's AVX2 kernel has 8 lanes.
[[maybe_unused]] VISVOL_SIMD_INLINE void store_levels_8(const Lanes<8>::I& k, std::uint8_t* dst) {
  typedef std::uint8_t Wide __attribute__((vector_size(32)));
  typedef std::uint8_t Bytes __attribute__((vector_size(8)));
  const Wide w = reinterpret_cast<const Wide&>(k);
  const Bytes b = __builtin_shufflevector(w, w, 0, 4, 8, 12, 16, 20, 24, 28);
  simd::store_unaligned(dst, b);
}
#endif

template <int W>
VISVOL_SIMD_INLINE void store_levels(const typename Lanes<W>::I& k, std::uint8_t* dst) {
#ifdef VISVOL_SHUFFLE_LEVELS_8
  if constexpr (W == 8) {
    store_levels_8(k, dst);
    return;
  }
#endif
  typedef std::uint8_t Bytes __attribute__((vector_size(W)));
  Bytes b = __builtin_convertvector(k, Bytes);
#if defined(__x86_64__)
  if constexpr (W == 16) __asm__("" : "+x"(b));  // keeps the narrowing in a register
#endif
  std::memcpy(dst, &b, sizeof b);
}

// Calls fn(n) for the entries n of ring m (ring_index order) whose offset
// lies within [dx_lo, dx_hi] x [dy_lo, dy_hi]. The others are not needed:
// where a sight line to a target inside the grid crosses ring m - 1, the
// crossing lies inside the grid (the grid is convex) and so do the posts
// either side of it on that grid line (the grid's edges are grid lines), so
// a target's stencil cells are inside whenever it is. The ring buffer's
// slots of the skipped entries keep older values, which only lanes whose
// observer or target lies outside the grid read, and their levels are never
// used.
template <class Fn>
VISVOL_SIMD_INLINE void for_each_inside_entry(int m, int dx_lo, int dx_hi, int dy_lo, int dy_hi, Fn&& fn) {
  const int x0 = std::max(-m, dx_lo), x1 = std::min(m, dx_hi);
  if (-m >= dy_lo && -m <= dy_hi) {  // the top row
    for (int dx = x0; dx <= x1; ++dx) fn(dx + m);
  }
  const bool left = -m >= dx_lo && -m <= dx_hi, right = m >= dx_lo && m <= dx_hi;
  const int y0 = std::max(-m + 1, dy_lo), y1 = std::min(m - 1, dy_hi);
  for (int dy = y0; dy <= y1; ++dy) {  // the sides, left then right on each row
    const int n = 2 * m + 1 + 2 * (dy + m - 1);
    if (left) fn(n);
    if (right) fn(n + 1);
  }
  if (m >= dy_lo && m <= dy_hi) {  // the bottom row
    for (int dx = x0; dx <= x1; ++dx) fn((2 * m + 1) + 2 * (2 * m - 1) + (dx + m));
  }
}

// Lanes [lane0, lane0 + R W) of the chunk: R registers of W lanes, so that
// the table walk and the scalar work of each entry (its fields, the bounds
// and offset of its write) are paid once for R W observers.
template <int W, int R>
VISVOL_SIMD_INLINE void hull_pass(const HullTable& table, const PaddedTerrain& terrain, const LevelRowLayout& layout,
                                  const LevelMap& level_map, RangeShape shape, const ObserverChunk& chunk, int lane0,
                                  float* ring_a, float* ring_b, std::uint8_t* out) {
  // A copy: the byte stores to `out` could alias the caller's, which would
  // reload (and convert) its fields at every entry.
  const LevelMap levels = level_map;
  using VecF = typename Lanes<W>::F;
  using VecI = typename Lanes<W>::I;
  constexpr std::size_t N = static_cast<std::size_t>(R);  // array bounds
  const int px0 = chunk.px0;
  const int py = chunk.py;
  const int ci = px0 / kLanes;
  const int dx_first = layout.first_dx(px0);
  const int dx_last = layout.last_dx(px0);
  const float* t0 = terrain.height_m.data() + terrain.index(px0, py) + lane0;
  const std::int32_t* g0 = terrain.ground_level.data() + terrain.index(px0, py) + lane0;
  VecF eye[N];
  VecI floor_level[N];
  for (int r = 0; r < R; ++r) {
    load(eye[r], chunk.eye_m + lane0 + r * W);
    load(floor_level[r], chunk.floor_level + lane0 + r * W);
  }
  const bool sphere = shape == RangeShape::sphere;

  // The lowest level a target may take: on or above its ground, inside the
  // observer's range.
  auto lowest_level = [&](VecI(&k)[N], const HullEntry& e) {
    for (int r = 0; r < R; ++r) {
      load(k[r], g0 + e.t_own + r * W);
      max_into(k[r], floor_level[r]);
      if (sphere) {
        VecI bound;
        level_at_or_above<W>(bound, eye[r] - e.span_m, levels);
        max_into(k[r], bound);
      }
    }
  };
  // Targets of the chunk inside the grid: a lane's target is (px0 + lane + dx,
  // py + dy), so some lane's is inside when dx and dy lie within these.
  const int dy_first = -py, dy_last = layout.ny - 1 - py;
  auto inside = [&](const HullEntry& e) {
    return e.dy >= dy_first && e.dy <= dy_last && e.dx >= dx_first && e.dx <= dx_last;
  };
  // The levels of an entry inside: target (0, 0)'s place in `out`, then a
  // row of slots per dy and a slot per dx.
  std::uint8_t* const out_origin = out + layout.offset(py, py, ci, -dx_first) + lane0;
  const std::ptrdiff_t row_bytes = static_cast<std::ptrdiff_t>(layout.slots) * kLanes;
  auto write = [&](const HullEntry& e, const VecI(&k)[N]) {
    std::uint8_t* dst = out_origin + e.dy * row_bytes + e.dx * kLanes;
    for (int r = 0; r < R; ++r) store_levels<W>(k[r], dst + r * W);
  };
  // The slope from the eye to the target's own terrain.
  auto own_slope = [&](VecF(&s)[N], const HullEntry& e) {
    for (int r = 0; r < R; ++r) {
      load(s[r], t0 + e.t_own + r * W);
      s[r] = (s[r] - e.drop_m - eye[r]) / e.d_m;
    }
  };
  // An entry's slot of a ring buffer: this pass's lanes of it.
  auto slot = [&](float* ring, int n) { return ring + n * kLanes + lane0; };

  // Rings 0 and 1: no crossing, visible from the ground up.
  for (const HullEntry& e : table.inner()) {
    if (!inside(e)) continue;
    VecI k[N];
    lowest_level(k, e);
    write(e, k);
  }

  // Only rings that reach a target inside the grid matter (RangeShape::none).
  const int reach = std::max({px0 + kLanes - 1, layout.nx - 1 - px0, py, layout.ny - 1 - py});
  const int last_ring = std::min(table.radius(), reach);

  float* prev = ring_a;
  float* cur = ring_b;
  // Ring 1 passes on the slope to its own terrain (it has no crossings).
  for (const HullEntry& e : table.inner()) {
    if (e.dx == 0 && e.dy == 0) continue;
    VecF own[N];
    own_slope(own, e);
    float* dst = slot(prev, ring_index(e.dx, e.dy, 1));
    for (int r = 0; r < R; ++r) simd::store_unaligned(dst + r * W, own[r]);
  }
  for (int m = 2; m <= last_ring; ++m) {
    const HullEntry* ring = table.ring(m);
    const bool exact = m <= table.exact_rings();
    auto entry = [&](int n) VISVOL_SIMD_INLINE_LAMBDA {
      const HullEntry& e = ring[n];
      VecF h[N];
      VecF ta, tb;
      if (exact) {
        // Every crossing of the sight line.
        for (int r = 0; r < R; ++r) h[r] = VecF{} + kNoHorizon;
        for (const Crossing* c = table.crossings_begin(m, n); c != table.crossings_end(m, n); ++c) {
          for (int r = 0; r < R; ++r) {
            load(ta, t0 + c->ta + r * W);
            load(tb, t0 + c->tb + r * W);
            max_into(h[r], VecF((ta + c->t * (tb - ta) - c->drop_m - eye[r]) * c->inv_d));
          }
        }
      } else {
        // Horizon over the far crossings, interpolated between the stencil cells,
        // and exact slopes at the two nearest crossings.
        const float* sa = slot(prev, e.a);
        const float* sb = slot(prev, e.b);
        for (int r = 0; r < R; ++r) {
          VecF ha, hb;
          load(ha, sa + r * W);
          load(hb, sb + r * W);
          h[r] = ha + e.t * (hb - ha);
          load(ta, t0 + e.ta + r * W);
          load(tb, t0 + e.tb + r * W);
          max_into(h[r], VecF((ta + e.t * (tb - ta) - e.drop1_m - eye[r]) * e.inv_d1));
          load(ta, t0 + e.tc + r * W);
          load(tb, t0 + e.td + r * W);
          max_into(h[r], VecF((ta + e.t2 * (tb - ta) - e.drop2_m - eye[r]) * e.inv_d2));
        }
      }
      // Rays beyond pass next to this cell: its own terrain is part of their horizon.
      VecF next[N];
      own_slope(next, e);
      float* dst = slot(cur, n);
      for (int r = 0; r < R; ++r) {
        max_into(next[r], h[r]);
        simd::store_unaligned(dst + r * W, next[r]);
      }
      // Lowest visible height over the target.
      VecI k[N], lowest[N];
      for (int r = 0; r < R; ++r) level_above<W>(k[r], eye[r] + e.d_m * h[r] + e.drop_m, levels);
      lowest_level(lowest, e);
      for (int r = 0; r < R; ++r) max_into(k[r], lowest[r]);
      write(e, k);
    };
    for_each_inside_entry(m, dx_first, dx_last, dy_first, dy_last, entry);
    std::swap(prev, cur);
  }
}

// The chunk in passes of R registers of W lanes.
template <int W, int R = 1>
VISVOL_SIMD_INLINE void hull_chunk(const HullTable& table, const PaddedTerrain& terrain, const LevelRowLayout& layout,
                                   const LevelMap& levels, RangeShape shape, const ObserverChunk& chunk, float* ring_a,
                                   float* ring_b, std::uint8_t* out) {
  static_assert(kLanes % (W * R) == 0, "passes cover the chunk");
  // The slots of entries outside the grid are not computed (see
  // for_each_inside_entry): they start the chunk at a fixed value, so that
  // every byte the kernel writes depends on this chunk alone (not on what the
  // buffers held before: the widths compare equal byte for byte).
  const std::size_t ring_floats = static_cast<std::size_t>(ring_size(table.radius())) * kLanes;
  std::fill(ring_a, ring_a + ring_floats, kNoHorizon);
  std::fill(ring_b, ring_b + ring_floats, kNoHorizon);
  for (int lane0 = 0; lane0 < kLanes; lane0 += W * R) {
    hull_pass<W, R>(table, terrain, layout, levels, shape, chunk, lane0, ring_a, ring_b, out);
  }
}

}  // namespace

// The kernel for the CPU it runs on, picked once (x86-64 levels v4: AVX-512,
// v3: AVX2, else the baseline), by GCC builds; others take the baseline.
// Under the sanitizers every load is checked: there the kernel reads whole
// 16-lane vectors whatever the CPU (fewer checks than narrower passes).
#if defined(VISVOL_SANITIZED) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
[[maybe_unused]] constexpr int kAvx2Width = 16;  // (clang builds have no AVX2 kernel)
constexpr int kBaselineWidth = 16;
#else
[[maybe_unused]] constexpr int kAvx2Width = 8;
constexpr int kBaselineWidth = 4;
#endif
namespace {

#ifdef VISVOL_SIMD_DISPATCH
using ChunkFn = void (*)(const HullTable&, const PaddedTerrain&, const LevelRowLayout&, const LevelMap&, RangeShape,
                         const ObserverChunk&, float*, float*, std::uint8_t*);

__attribute__((target("arch=x86-64-v4"))) void hull_chunk_v4(const HullTable& table, const PaddedTerrain& terrain,
                                                             const LevelRowLayout& layout, const LevelMap& levels,
                                                             RangeShape shape, const ObserverChunk& chunk,
                                                             float* ring_a, float* ring_b, std::uint8_t* out) {
  hull_chunk<16>(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
}

__attribute__((target("arch=x86-64-v3"))) void hull_chunk_v3(const HullTable& table, const PaddedTerrain& terrain,
                                                             const LevelRowLayout& layout, const LevelMap& levels,
                                                             RangeShape shape, const ObserverChunk& chunk,
                                                             float* ring_a, float* ring_b, std::uint8_t* out) {
  hull_chunk<kAvx2Width, kLanes / kAvx2Width>(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
}
#endif

void hull_chunk_baseline(const HullTable& table, const PaddedTerrain& terrain, const LevelRowLayout& layout,
                         const LevelMap& levels, RangeShape shape, const ObserverChunk& chunk, float* ring_a,
                         float* ring_b, std::uint8_t* out) {
  hull_chunk<kBaselineWidth>(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
}

#ifdef VISVOL_SIMD_DISPATCH
ChunkFn pick_hull_chunk() { return simd::pick_for_cpu<ChunkFn>(hull_chunk_v4, hull_chunk_v3, hull_chunk_baseline); }
#endif

}  // namespace

void hull_levels_chunk(const HullTable& table, const PaddedTerrain& terrain, const LevelRowLayout& layout,
                       const LevelMap& levels, RangeShape shape, const ObserverChunk& chunk, float* ring_a,
                       float* ring_b, std::uint8_t* out) {
#ifdef VISVOL_SIMD_DISPATCH
  static const ChunkFn chunk_fn = pick_hull_chunk();
  chunk_fn(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
#else
  hull_chunk_baseline(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
#endif
}

int hull_kernel_width() {
#ifdef VISVOL_SIMD_DISPATCH
  const ChunkFn f = pick_hull_chunk();
  return f == hull_chunk_v4 ? 16 : f == hull_chunk_v3 ? kAvx2Width : kBaselineWidth;
#else
  return kBaselineWidth;
#endif
}

bool hull_levels_chunk_at_width(int width, const HullTable& table, const PaddedTerrain& terrain,
                                const LevelRowLayout& layout, const LevelMap& levels, RangeShape shape,
                                const ObserverChunk& chunk, float* ring_a, float* ring_b, std::uint8_t* out) {
#ifdef VISVOL_SIMD_DISPATCH
  __builtin_cpu_init();
  if (width == 16 && __builtin_cpu_supports("x86-64-v4")) {
    hull_chunk_v4(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
    return true;
  }
  if (width == kAvx2Width && __builtin_cpu_supports("x86-64-v3")) {
    hull_chunk_v3(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
    return true;
  }
#endif
  if (width != kBaselineWidth) return false;
  hull_chunk_baseline(table, terrain, layout, levels, shape, chunk, ring_a, ring_b, out);
  return true;
}

void observer_horizon(const PaddedTerrain& terrain, int radius, int exact_rings, double spacing_m,
                      double curvature_coeff, int pi, int pj, double eye_z_m, std::vector<float>& horizon,
                      bool grid_only) {
  const int side = 2 * radius + 1;
  horizon.assign(static_cast<std::size_t>(side) * static_cast<std::size_t>(side), kNoHorizon);
  const float* t0 = terrain.height_m.data() + terrain.index(pi, pj);
  const double eye = eye_z_m;
  // Ring 1 passes on the slope to its own terrain (it has no crossings).
  std::vector<float> prev(static_cast<std::size_t>(ring_size(1)), kNoHorizon);
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const double d = std::hypot(double(dx), double(dy)) * spacing_m;
      prev[static_cast<std::size_t>(ring_index(dx, dy, 1))] =
          static_cast<float>((t0[dy * terrain.stride + dx] - curvature_drop_m(curvature_coeff, d) - eye) / d);
    }
  }
  std::vector<float> cur;
  std::vector<HullEntry> ring;
  std::vector<Crossing> crossings;
  auto lerp_terrain = [&](std::int32_t a, std::int32_t b, double t) {
    return t0[a] + t * (static_cast<double>(t0[b]) - t0[a]);
  };
  // grid-only targets read at most a post past the grid (ring 1), the others
  // up to the radius
  assert(terrain.pad >= (grid_only ? 1 : radius + 1));
  OffsetBox box;
  int last_ring = radius;
  if (grid_only) {
    box = {-pi, terrain.nx - 1 - pi, -pj, terrain.ny - 1 - pj};
    last_ring = std::min(radius, std::max({pi, terrain.nx - 1 - pi, pj, terrain.ny - 1 - pj}));
  }
  for (int m = 2; m <= last_ring; ++m) {
    ring.clear();
    append_ring_entries(m, spacing_m, curvature_coeff, RangeShape::none, 0.0, terrain.stride, ring, box);
    cur.assign(ring.size(), kNoHorizon);
    for (std::size_t n = 0; n < ring.size(); ++n) {
      const HullEntry& e = ring[n];
      if (grid_only && e.d_m == 0) continue;  // outside the box: left HullEntry{}
      double h = kNoHorizon;
      if (m <= exact_rings) {
        crossings.clear();
        append_crossings(e.dx, e.dy, spacing_m, curvature_coeff, terrain.stride, crossings);
        for (const Crossing& c : crossings) {
          h = std::max(h, (lerp_terrain(c.ta, c.tb, c.t) - c.drop_m - eye) * c.inv_d);
        }
      } else {
        const double ha = prev[e.a], hb = prev[e.b];
        const double s1 = (lerp_terrain(e.ta, e.tb, e.t) - e.drop1_m - eye) * e.inv_d1;
        const double s2 = (lerp_terrain(e.tc, e.td, e.t2) - e.drop2_m - eye) * e.inv_d2;
        h = std::max(ha + e.t * (hb - ha), std::max(s1, s2));
      }
      const double own = (t0[e.dy * terrain.stride + e.dx] - e.drop_m - eye) / e.d_m;
      cur[n] = static_cast<float>(std::max(h, own));
      horizon[static_cast<std::size_t>(e.dy + radius) * static_cast<std::size_t>(side) +
              static_cast<std::size_t>(e.dx + radius)] = static_cast<float>(h);
    }
    prev.swap(cur);
  }
}

}  // namespace visvol::fields
