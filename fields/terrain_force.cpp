#include "fields/terrain_force.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>

#include "fields/simd.hpp"
#include "fields/worker_pool.hpp"

namespace visvol::fields {

namespace {

using Vec3 = Eigen::Vector3d;

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct Nearest {
  Vec3 point = Vec3::Zero();
  double distance2 = std::numeric_limits<double>::infinity();
};

// The closest points to q of cell (i, j)'s two triangles (split along its
// north-west to south-east diagonal), kept in `best` where nearer.
void visit_cell(const Heightfield& hf, int i, int j, const Vec3& q, Nearest& best) {
  const double s = hf.spacing_m;
  const double h00 = hf.at(i, j), h10 = hf.at(i + 1, j), h01 = hf.at(i, j + 1), h11 = hf.at(i + 1, j + 1);
  const Vec3 a{i * s, j * s, h00}, b{(i + 1) * s, j * s, h10};
  const Vec3 c{(i + 1) * s, (j + 1) * s, h11}, d{i * s, (j + 1) * s, h01};
  for (const Vec3& p : {closest_on_triangle(q, a, b, c), closest_on_triangle(q, a, c, d)}) {
    const double d2 = (p - q).squaredNorm();
    if (d2 < best.distance2) best = {p, d2};
  }
}

// Searches the cells whose squares come within `search_m` of q (local frame),
// nearest cells first, skipping any cell that cannot hold a closer point: its
// distance is at least the horizontal distance to its square and the vertical
// gap to its height range.
Nearest nearest_local(const Heightfield& hf, const Vec3& q, double search_m) {
  const double s = hf.spacing_m;
  const int i_lo = std::max(0, static_cast<int>(std::floor((q.x() - search_m) / s)));
  const int i_hi = std::min(hf.nx - 2, static_cast<int>(std::floor((q.x() + search_m) / s)));
  const int j_lo = std::max(0, static_cast<int>(std::floor((q.y() - search_m) / s)));
  const int j_hi = std::min(hf.ny - 2, static_cast<int>(std::floor((q.y() + search_m) / s)));
  const int ci = std::clamp(static_cast<int>(std::floor(q.x() / s)), i_lo, std::max(i_lo, i_hi));
  const int cj = std::clamp(static_cast<int>(std::floor(q.y() / s)), j_lo, std::max(j_lo, j_hi));
  Nearest best;
  auto visit = [&](int i, int j) {
    const double gap_x = std::max({0.0, i * s - q.x(), q.x() - (i + 1) * s});
    const double gap_y = std::max({0.0, j * s - q.y(), q.y() - (j + 1) * s});
    const double h00 = hf.at(i, j), h10 = hf.at(i + 1, j), h01 = hf.at(i, j + 1), h11 = hf.at(i + 1, j + 1);
    const double hmax = std::max({h00, h10, h01, h11}), hmin = std::min({h00, h10, h01, h11});
    const double gap_z = std::max({0.0, q.z() - hmax, hmin - q.z()});
    if (gap_x * gap_x + gap_y * gap_y + gap_z * gap_z >= best.distance2) return;
    visit_cell(hf, i, j, q, best);
  };
  // Rings of cells around the one under q.
  const int rings = std::max({ci - i_lo, i_hi - ci, cj - j_lo, j_hi - cj});
  for (int r = 0; r <= rings; ++r) {
    // A ring's nearest cell is at least (r - 1) cells away horizontally.
    const double ring_gap = std::max(0, r - 1) * s;
    if (ring_gap * ring_gap >= best.distance2) break;
    for (int j = cj - r; j <= cj + r; ++j) {
      if (j < j_lo || j > j_hi) continue;
      const bool edge_row = j == cj - r || j == cj + r;
      for (int i = ci - r; i <= ci + r; i += edge_row ? 1 : 2 * r) {
        if (i >= i_lo && i <= i_hi) visit(i, j);
        if (r == 0) break;
      }
    }
  }
  return best;
}

// A cell near a post, and the horizontal distance from the post to it:
// cell (di, dj) spans posts i + di .. i + di + 1 and j + dj .. j + dj + 1.
struct CellOffset {
  int di = 0, dj = 0;
  double gap2_m2 = 0;  // squared horizontal distance from the post to the cell's square
};

// Every cell within `reach` cells of a post, nearest first: the order in
// which a search from a post meets the cells, the same for every post.
std::vector<CellOffset> cells_by_distance(int reach, double spacing_m) {
  std::vector<CellOffset> out;
  for (int dj = -reach - 1; dj <= reach; ++dj) {
    for (int di = -reach - 1; di <= reach; ++di) {
      const int gx = std::max({0, di, -di - 1}), gy = std::max({0, dj, -dj - 1});  // whole cells between
      out.push_back({di, dj, (double(gx) * gx + double(gy) * gy) * spacing_m * spacing_m});
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const CellOffset& a, const CellOffset& b) { return a.gap2_m2 < b.gap2_m2; });
  return out;
}

// The height range of every terrain cell over a band of cell rows, held
// contiguously: the band's nearest-point search rules out most cells in its
// reach by their range alone (one load, not four scattered posts).
class CellRanges {
 public:
  // Cell rows [row_begin, row_end) of hf, clamped to the grid's cells; the
  // searches reach `reach` cells from their post.
  CellRanges(const Heightfield& hf, int row_begin, int row_end, int reach)
      : hf_(hf),
        ncx_(hf.nx - 1),
        j0_(std::max(0, row_begin)),
        j1_(std::min(hf.ny - 1, row_end)),
        order_(cells_by_distance(reach, hf.spacing_m)) {
    range_.resize(static_cast<std::size_t>(ncx_) * static_cast<std::size_t>(std::max(0, j1_ - j0_)));
    for (int j = j0_; j < j1_; ++j) {
      for (int i = 0; i < ncx_; ++i) {
        const float h00 = hf.at(i, j), h10 = hf.at(i + 1, j), h01 = hf.at(i, j + 1), h11 = hf.at(i + 1, j + 1);
        range_[index(i, j)] = {std::min({h00, h10, h01, h11}), std::max({h00, h10, h01, h11})};
      }
    }
  }

  struct Range {
    float lo, hi;
  };
  const Heightfield& terrain() const { return hf_; }
  const std::vector<CellOffset>& order() const { return order_; }
  // The range of cell (ci, cj), or null where the rows held have no such cell.
  const Range* range(int ci, int cj) const {
    return ci < 0 || ci >= ncx_ || cj < j0_ || cj >= j1_ ? nullptr : &range_[index(ci, cj)];
  }

 private:
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j - j0_) * static_cast<std::size_t>(ncx_) + static_cast<std::size_t>(i);
  }

  const Heightfield& hf_;
  int ncx_, j0_, j1_;  // cells per row; the cell rows held, [j0_, j1_)
  std::vector<CellOffset> order_;
  std::vector<Range> range_;
};

// ---- the band's search, a column at a time --------------------------------
//
// The band samples of one column share their post: the cells a search meets,
// in the same order, and the triangles' corners. Only their heights differ.
// So a column is searched once, its samples W at a time in the lanes of a
// vector (4 doubles with AVX2 or AVX-512, 2 on the baseline's SSE2), each
// lane keeping its own nearest point; a cell is visited when any lane's bound
// admits it, and the search ends at the first cell no nearer than every
// lane's best. A lane that did not need a visit only keeps the nearer point,
// so every lane ends on its exact nearest point, as the search from its own
// post does.

template <int W>
using DLanes = simd::Lanes<W>;

// A point per lane: x, y, z.
template <int W>
struct PointLanes {
  typename DLanes<W>::D x, y, z;
};

// Is any lane of a comparison's result set? (Narrowed to a byte a lane and
// tested as one integer: a lane by lane test extracts every lane.)
template <int W>
VISVOL_SIMD_INLINE bool any_lane(const typename DLanes<W>::M& m) {
  typedef std::int8_t Bytes __attribute__((vector_size(W)));
  const Bytes b = __builtin_convertvector(m, Bytes);
  std::uint64_t bits = 0;
  std::memcpy(&bits, &b, sizeof b);
  return bits != 0;
}

// The closest point of triangle abc to q = (qx, qy, qz[lane]) in every lane:
// closest_on_triangle's Voronoi regions, each lane taking its own. No
// division can be by zero: d1 - d3 = |ab|^2, d2 - d6 = |ac|^2,
// (d4 - d3) + (d5 - d6) = |bc|^2 and va + vb + vc = |ab x ac|^2.
template <int W>
VISVOL_SIMD_INLINE void closest_on_triangle_lanes(double qx, double qy, const typename DLanes<W>::D& qz, const Vec3& a,
                                                  const Vec3& b, const Vec3& c, PointLanes<W>& out) {
  using D = typename DLanes<W>::D;
  using M = typename DLanes<W>::M;
  const Vec3 ab = b - a, ac = c - a;
  // dot(u, q - p) for a corner p: the horizontal part is the same in every lane
  // (vectors pass by reference: by value, one wider than the baseline's
  // registers would change the calling convention)
  auto dot = [&](D& out_d, const Vec3& u, const Vec3& p) VISVOL_SIMD_INLINE_LAMBDA {
    out_d = (u.x() * (qx - p.x()) + u.y() * (qy - p.y())) + u.z() * (qz - p.z());
  };
  D d1, d2, d3, d4, d5, d6;
  dot(d1, ab, a);
  dot(d2, ac, a);
  dot(d3, ab, b);
  dot(d4, ac, b);
  dot(d5, ab, c);
  dot(d6, ac, c);
  const D vc = d1 * d4 - d3 * d2;
  const D vb = d5 * d2 - d1 * d6;
  const D va = d3 * d6 - d5 * d4;
  // point p + u t where the lane's region holds
  auto along = [&](const M& region, const Vec3& p, const Vec3& u, const D& t) VISVOL_SIMD_INLINE_LAMBDA {
    out.x = region ? p.x() + u.x() * t : out.x;
    out.y = region ? p.y() + u.y() * t : out.y;
    out.z = region ? p.z() + u.z() * t : out.z;
  };
  auto corner = [&](const M& region, const Vec3& p) VISVOL_SIMD_INLINE_LAMBDA {
    out.x = region ? D{} + p.x() : out.x;
    out.y = region ? D{} + p.y() : out.y;
    out.z = region ? D{} + p.z() : out.z;
  };
  // the interior, then each region over it, the first that holds last
  const D denom = 1.0 / (va + vb + vc);
  const D v = vb * denom, w = vc * denom;
  out.x = a.x() + ab.x() * v + ac.x() * w;
  out.y = a.y() + ab.y() * v + ac.y() * w;
  out.z = a.z() + ab.z() * v + ac.z() * w;
  const D zero{};
  along((va <= zero) & ((d4 - d3) >= zero) & ((d5 - d6) >= zero), b, c - b, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  along((vb <= zero) & (d2 >= zero) & (d6 <= zero), a, ac, d2 / (d2 - d6));
  corner((d6 >= zero) & (d5 <= d6), c);
  along((vc <= zero) & (d1 >= zero) & (d3 <= zero), a, ab, d1 / (d1 - d3));
  corner((d3 >= zero) & (d4 <= d3), b);
  corner((d1 <= zero) & (d2 <= zero), a);
}

// The nearest points found so far for W samples of a column.
template <int W>
struct ColumnLanes {
  typename DLanes<W>::D z;      // the samples' heights
  typename DLanes<W>::D best2;  // squared distance to the nearest point found
  PointLanes<W> best;           // that point
};

// visit_cell for every lane: cell (ci, cj)'s two triangles.
template <int W>
VISVOL_SIMD_INLINE void visit_cell_lanes(const Heightfield& hf, int ci, int cj, double qx, double qy, double gap2_m2,
                                         ColumnLanes<W>& lanes) {
  using D = typename DLanes<W>::D;
  const double s = hf.spacing_m;
  const double h00 = hf.at(ci, cj), h10 = hf.at(ci + 1, cj), h01 = hf.at(ci, cj + 1), h11 = hf.at(ci + 1, cj + 1);
  const Vec3 a{ci * s, cj * s, h00}, b{(ci + 1) * s, cj * s, h10};
  const Vec3 c{(ci + 1) * s, (cj + 1) * s, h11}, d{ci * s, (cj + 1) * s, h01};
  for (int t = 0; t < 2; ++t) {
    const Vec3& p1 = t == 0 ? b : c;
    const Vec3& p2 = t == 0 ? c : d;
    // the cell's bound with the triangle's own heights: most visits need one triangle
    const double lo = std::min({a.z(), p1.z(), p2.z()}), hi = std::max({a.z(), p1.z(), p2.z()});
    const D above = lanes.z - hi, below = lo - lanes.z;
    D gap = above > below ? above : below;
    gap = gap > D{} ? gap : D{};
    if (!any_lane<W>(gap2_m2 + gap * gap < lanes.best2)) continue;
    PointLanes<W> p;
    closest_on_triangle_lanes<W>(qx, qy, lanes.z, a, p1, p2, p);
    const D ex = p.x - qx, ey = p.y - qy, ez = p.z - lanes.z;
    const D d2 = ex * ex + ey * ey + ez * ez;
    const typename DLanes<W>::M nearer = d2 < lanes.best2;
    lanes.best2 = nearer ? d2 : lanes.best2;
    lanes.best.x = nearer ? p.x : lanes.best.x;
    lanes.best.y = nearer ? p.y : lanes.best.y;
    lanes.best.z = nearer ? p.z : lanes.best.z;
  }
}

// The search of the column over post (i, j) for heights z_m[0..count)
// (count <= kMaxBandLevels), W lanes at a time. Each lane starts from the post,
// on the surface straight above or below it.
template <int W>
VISVOL_SIMD_INLINE void column_search(const CellRanges& cells, int i, int j, const double* z_m, int count,
                                      Nearest* out) {
  using D = typename DLanes<W>::D;
  constexpr std::size_t kMaxVectors = (kMaxBandLevels + W - 1) / W;
  const Heightfield& hf = cells.terrain();
  const double qx = i * hf.spacing_m, qy = j * hf.spacing_m, ground = hf.at(i, j);
  const int vectors = (count + W - 1) / W;
  ColumnLanes<W> lanes[kMaxVectors];
  for (int v = 0; v < vectors; ++v) {
    for (int l = 0; l < W; ++l) lanes[v].z[l] = z_m[std::min(v * W + l, count - 1)];  // spare lanes repeat the last
    const D dz = lanes[v].z - ground;
    lanes[v].best2 = dz * dz;
    lanes[v].best.x = D{} + qx;
    lanes[v].best.y = D{} + qy;
    lanes[v].best.z = D{} + ground;
  }
  // The largest best distance of a vector's lanes: where its search may end.
  auto farthest2 = [&](int v) VISVOL_SIMD_INLINE_LAMBDA {
    double out_m2 = 0;
    for (int l = 0; l < W; ++l) out_m2 = std::max(out_m2, double(lanes[v].best2[l]));
    return out_m2;
  };
  // reach2[v] is an upper bound of farthest2(v) (the best distances only
  // shrink), brought up to date only where the vector's search would end on
  // it; a vector whose search ended leaves `live`.
  double reach2[kMaxVectors];
  for (int v = 0; v < vectors; ++v) reach2[v] = farthest2(v);
  int live = vectors;
  int first_live = 0;  // vectors below it have ended
  bool ended[kMaxVectors] = {};
  for (const CellOffset& o : cells.order()) {
    const CellRanges::Range* r = nullptr;
    for (int v = first_live; v < vectors; ++v) {
      if (ended[v]) continue;
      if (o.gap2_m2 >= reach2[v]) {
        reach2[v] = farthest2(v);
        if (o.gap2_m2 >= reach2[v]) {
          ended[v] = true;
          --live;
          continue;
        }
      }
      if (!r) {
        r = cells.range(i + o.di, j + o.dj);
        if (!r) break;  // a cell outside the rows held: none of the lanes needs it
      }
      // the bound of the search from a post: the square's distance and the
      // vertical gap to the cell's height range
      const D above = lanes[v].z - static_cast<double>(r->hi), below = static_cast<double>(r->lo) - lanes[v].z;
      D gap = above > below ? above : below;
      gap = gap > D{} ? gap : D{};
      if (any_lane<W>(o.gap2_m2 + gap * gap < lanes[v].best2))
        visit_cell_lanes<W>(hf, i + o.di, j + o.dj, qx, qy, o.gap2_m2, lanes[v]);
    }
    if (live == 0) break;
    while (first_live < vectors && ended[first_live]) ++first_live;
  }
  for (int n = 0; n < count; ++n) {
    const ColumnLanes<W>& c = lanes[n / W];
    const int l = n % W;
    out[n] = {Vec3(c.best.x[l], c.best.y[l], c.best.z[l]), c.best2[l]};
  }
}

// The search at the CPU's best width, picked once (GCC builds on x86-64:
// x86-64 levels v4 and v3; others take the baseline). Four lanes on v4 as on
// v3: on a 2-core AMD EPYC VM (Zen 4) the 8-lane AVX-512 search took 1.7
// times as long as the 4-lane one with AVX-512's masks, which took a fifth
// less than AVX2's (tools/bench/README.md, "Field build"). The baseline's 2
// lanes (SSE2; and every clang or non-x86 build) are no gain: 0.84 s there
// against 0.78 s for the search one sample at a time that this replaced.

using ColumnFn = void (*)(const CellRanges&, int, int, const double*, int, Nearest*);

void column_search_baseline(const CellRanges& cells, int i, int j, const double* z_m, int count, Nearest* out) {
  column_search<2>(cells, i, j, z_m, count, out);
}

#ifdef VISVOL_SIMD_DISPATCH
__attribute__((target("arch=x86-64-v4"))) void column_search_v4(const CellRanges& cells, int i, int j,
                                                                const double* z_m, int count, Nearest* out) {
  column_search<4>(cells, i, j, z_m, count, out);
}
__attribute__((target("arch=x86-64-v3"))) void column_search_v3(const CellRanges& cells, int i, int j,
                                                                const double* z_m, int count, Nearest* out) {
  column_search<4>(cells, i, j, z_m, count, out);
}
ColumnFn pick_column_search() {
  return simd::pick_for_cpu<ColumnFn>(column_search_v4, column_search_v3, column_search_baseline);
}
#endif

ColumnFn column_search_for_cpu() {
#ifdef VISVOL_SIMD_DISPATCH
  static const ColumnFn fn = pick_column_search();
  return fn;
#else
  return column_search_baseline;
#endif
}

// The band sample at height z over post (i, j), from its nearest point n.
TffSample band_sample(const Heightfield& hf, int i, int j, double z, const Nearest& n) {
  const Vec3 q{i * hf.spacing_m, j * hf.spacing_m, z};
  const bool inside = z < hf.at(i, j);
  const Vec3 e = inside ? Vec3(n.point - q) : Vec3(q - n.point);  // outward, local axes
  TffSample out;
  out.dx_m = static_cast<float>(e.x());
  out.dy_m = static_cast<float>(-e.y());  // local v is south; world y is north
  out.dz_m = static_cast<float>(e.z());
  const double dist = std::sqrt(n.distance2);
  out.signed_distance_m = static_cast<float>(inside ? -dist : dist);
  return out;
}

}  // namespace

Status validate(const TffParams& p) {
  std::ostringstream msg;
  if (!(p.band_offset_m >= kMinBandOffsetM && p.band_offset_m <= kMaxBandOffsetM)) {  // NaN too
    msg << "terrain force band offset: " << p.band_offset_m << " m is outside " << kMinBandOffsetM << ".."
        << kMaxBandOffsetM << " m";
    return invalid_argument(msg.str());
  }
  if (p.band_levels < 2 || p.band_levels > kMaxBandLevels) {
    msg << "terrain force band levels: " << p.band_levels << " is outside 2.." << kMaxBandLevels;
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

int tff_reach_posts(const TffParams& p, double spacing_m) {
  const double posts = std::ceil(p.band_offset_m / spacing_m) + 1;
  return posts < 1e9 ? static_cast<int>(posts) : 1000000000;  // (NaN and infinity: the most)
}

Status validate(const TffParams& p, double spacing_m) {
  VISVOL_RETURN_IF_ERROR(validate(p));
  const int reach = tff_reach_posts(p, spacing_m);
  if (!(spacing_m > 0) || reach > kMaxTffReachPosts) {
    std::ostringstream msg;
    msg << "terrain force band: +-" << p.band_offset_m << " m over posts " << spacing_m << " m apart reaches " << reach
        << " posts, more than " << kMaxTffReachPosts
        << " (its nearest-point search grows with the square of that): use a smaller --tff-offset (at most "
        << (kMaxTffReachPosts - 1) * spacing_m << " m here) or coarser posts (--spacing)";
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

NearestTerrainPoint nearest_terrain_point(const Heightfield& hf, const Eigen::Vector3d& q_m, double search_m) {
  // World to local: u = x - origin_x, v = origin_y - y.
  const Vec3 q{q_m.x() - hf.origin_x, hf.origin_y - q_m.y(), q_m.z()};
  const Nearest n = nearest_local(hf, q, search_m);
  NearestTerrainPoint out;
  out.point_m = {n.point.x() + hf.origin_x, hf.origin_y - n.point.y(), n.point.z()};
  out.distance_m = std::sqrt(n.distance2);
  return out;
}

namespace {

void band_rows(ColumnFn search, const Heightfield& hf, const TffParams& params, int j_begin, int j_end, TffSample* out,
               WorkerPool* pool) {
  // the column's samples live on the stack: validate(params) is every caller's precondition
  assert(params.band_levels >= 2 && params.band_levels <= kMaxBandLevels);
  if (params.band_levels < 2 || params.band_levels > kMaxBandLevels) return;
  const std::size_t nx = static_cast<std::size_t>(hf.nx);
  const std::size_t levels = static_cast<std::size_t>(params.band_levels);
  // every cell a search from these rows can reach: within the band's offset
  const int reach = tff_reach_posts(params, hf.spacing_m);
  const CellRanges cells(hf, j_begin - reach - 1, j_end + reach, reach);
  auto row = [&](int item, int) {
    const int j = j_begin + item;
    double z_m[kMaxBandLevels];
    Nearest nearest[kMaxBandLevels];
    for (int i = 0; i < hf.nx; ++i) {
      const double ground = hf.at(i, j);
      for (int b = 0; b < params.band_levels; ++b) z_m[b] = ground - params.band_offset_m + b * params.step_m();
      search(cells, i, j, z_m, params.band_levels, nearest);
      for (int b = 0; b < params.band_levels; ++b) {
        out[(static_cast<std::size_t>(j - j_begin) * levels + static_cast<std::size_t>(b)) * nx +
            static_cast<std::size_t>(i)] = band_sample(hf, i, j, z_m[b], nearest[b]);
      }
    }
  };
  if (pool) {
    pool->run(j_end - j_begin, row);
  } else {
    for (int j = j_begin; j < j_end; ++j) row(j - j_begin, 0);
  }
}

}  // namespace

void terrain_force_rows(const Heightfield& hf, const TffParams& params, int j_begin, int j_end, TffSample* out,
                        WorkerPool* pool) {
  band_rows(column_search_for_cpu(), hf, params, j_begin, j_end, out, pool);
}

void terrain_force_rows_baseline(const Heightfield& hf, const TffParams& params, int j_begin, int j_end,
                                 TffSample* out) {
  band_rows(column_search_baseline, hf, params, j_begin, j_end, out, nullptr);
}

}  // namespace visvol::fields
