#include "fields/terrain_force.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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

  // The nearest point of the surface to q, a point above or below post
  // (i, j) (local frame), among points nearer than `best` on entry (a
  // surface point known to be near). The cells are met nearest first, so the
  // search ends at the first whose square is no nearer than the best point
  // found; the caller's rows must hold every cell that near.
  Nearest nearest_over_post(int i, int j, const Vec3& q, Nearest best) const {
    for (const CellOffset& o : order_) {
      if (o.gap2_m2 >= best.distance2) break;
      const int ci = i + o.di, cj = j + o.dj;
      if (ci < 0 || ci >= ncx_ || cj < j0_ || cj >= j1_) continue;
      const Range& r = range_[index(ci, cj)];
      const double gap_z = std::max({0.0, q.z() - r.hi, r.lo - q.z()});
      if (o.gap2_m2 + gap_z * gap_z >= best.distance2) continue;
      visit_cell(hf_, ci, cj, q, best);
    }
    return best;
  }

 private:
  struct Range {
    float lo, hi;
  };
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j - j0_) * static_cast<std::size_t>(ncx_) + static_cast<std::size_t>(i);
  }

  const Heightfield& hf_;
  int ncx_, j0_, j1_;  // cells per row; the cell rows held, [j0_, j1_)
  std::vector<CellOffset> order_;
  std::vector<Range> range_;
};

// One band sample. `previous` is the nearest point of the sample below it in
// its column (or none): the nearest point is no farther than that one, nor
// than the post below (or above) the sample, which is on the surface; the
// search starts from the nearer of the two.
TffSample band_sample(const CellRanges& cells, const Heightfield& hf, const TffParams& params, int i, int j, int b,
                      Nearest& previous) {
  const double ground = hf.at(i, j);
  const double z = ground - params.band_offset_m + b * params.step_m();
  const Vec3 q{i * hf.spacing_m, j * hf.spacing_m, z};
  Nearest seed{Vec3(q.x(), q.y(), ground), (z - ground) * (z - ground)};
  if (std::isfinite(previous.distance2)) {
    const double d2 = (previous.point - q).squaredNorm();
    if (d2 < seed.distance2) seed = {previous.point, d2};
  }
  const Nearest n = cells.nearest_over_post(i, j, q, seed);
  previous = n;
  const bool inside = z < ground;
  Vec3 e = inside ? Vec3(n.point - q) : Vec3(q - n.point);  // outward, local axes
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
  if (!std::isfinite(p.band_offset_m) || p.band_offset_m <= 0 || p.band_offset_m > 300.0) {
    msg << "terrain force band offset: " << p.band_offset_m << " m is outside (0, 300] m";
    return invalid_argument(msg.str());
  }
  if (p.band_levels < 2 || p.band_levels > 64) {
    msg << "terrain force band levels: " << p.band_levels << " is outside 2..64";
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

void terrain_force_rows(const Heightfield& hf, const TffParams& params, int j_begin, int j_end, TffSample* out,
                        WorkerPool* pool) {
  const std::size_t nx = static_cast<std::size_t>(hf.nx);
  const std::size_t levels = static_cast<std::size_t>(params.band_levels);
  // every cell a search from these rows can reach: within the band's offset
  const int reach = static_cast<int>(std::ceil(params.band_offset_m / hf.spacing_m)) + 1;
  const CellRanges cells(hf, j_begin - reach - 1, j_end + reach, reach);
  auto row = [&](int item, int) {
    const int j = j_begin + item;
    for (int i = 0; i < hf.nx; ++i) {
      Nearest previous;  // none yet in this column
      for (int b = 0; b < params.band_levels; ++b) {
        out[(static_cast<std::size_t>(j - j_begin) * levels + static_cast<std::size_t>(b)) * nx +
            static_cast<std::size_t>(i)] = band_sample(cells, hf, params, i, j, b, previous);
      }
    }
  };
  if (pool) {
    pool->run(j_end - j_begin, row);
  } else {
    for (int j = j_begin; j < j_end; ++j) row(j - j_begin, 0);
  }
}

}  // namespace visvol::fields
