#include "fields/exact_visibility.hpp"

#include <algorithm>
#include <cmath>

namespace visvol::fields {

namespace {

// Terrain at a point on a grid line: `along` is the fractional coordinate
// along the line (on the grid, up to rounding), `across` the integer
// coordinate of the line (a line of the grid).
// (Comparisons, not std::clamp: the exact reference runs under the
// sanitizers at -O1, where every std:: call stays a call.)
double terrain_on_line(const Heightfield& hf, bool vertical_line, int across, double along) {
  const int limit = vertical_line ? hf.ny - 1 : hf.nx - 1;
  along = along < 0 ? 0 : (along > limit ? limit : along);
  const double lo = std::floor(along);
  const int i0 = static_cast<int>(lo);
  const int i1 = i0 < limit ? i0 + 1 : limit;
  const double t = along - lo;
  const double h0 = vertical_line ? hf.at(across, i0) : hf.at(i0, across);
  if (t == 0) return h0;
  const double h1 = vertical_line ? hf.at(across, i1) : hf.at(i1, across);
  return h0 + t * (h1 - h0);
}

// Tests the crossings with grid lines of one direction (x = integer when
// `vertical_line`, else y = integer): the grid's own lines only, so a sight
// line reaching beyond the grid is judged over the terrain it crosses.
bool clear_of_lines(const Heightfield& hf, bool vertical_line, double ai, double aj, double az, double bi, double bj,
                    double bz, double d_total_m, double coeff) {
  const double a_main = vertical_line ? ai : aj;
  const double b_main = vertical_line ? bi : bj;
  const double a_other = vertical_line ? aj : ai;
  const double b_other = vertical_line ? bj : bi;
  if (a_main == b_main) return true;
  const double lo = std::min(a_main, b_main), hi = std::max(a_main, b_main);
  const int last_line = vertical_line ? hf.nx - 1 : hf.ny - 1;
  const double other_last = vertical_line ? hf.ny - 1 : hf.nx - 1;
  // the lines strictly between lo and hi, within the grid (bounded before
  // any conversion to int: the ends may lie anywhere)
  const double first = std::max(std::floor(lo) + 1.0, 0.0);
  const double last = std::min(std::ceil(hi) - 1.0, static_cast<double>(last_line));
  if (first > last) return true;
  const int line_end = static_cast<int>(last);
  for (int line = static_cast<int>(first); line <= line_end; ++line) {
    const double f = (line - a_main) / (b_main - a_main);  // 0 < f < 1
    const double along = a_other + f * (b_other - a_other);
    // off the grid: unknown terrain blocks nothing (an end on the grid's
    // edge may land a rounding step beyond it: still the edge)
    if (!(along >= -1e-9 && along <= other_last + 1e-9)) continue;
    const double d = f * d_total_m;
    const double ground = terrain_on_line(hf, vertical_line, line, along) - coeff * d * d / (2.0 * kEarthRadiusM);
    const double z = az + f * (bz - az);
    if (!(z > ground)) return false;
  }
  return true;
}

}  // namespace

bool r3_visible(const Heightfield& hf, double ai, double aj, double az_m, double bi, double bj, double bz_m,
                double curvature_coeff) {
  for (double v : {ai, aj, az_m, bi, bj, bz_m}) {
    if (!std::isfinite(v)) return false;  // no sight line to judge: never "clear"
  }
  const double d_total = std::hypot(bi - ai, bj - aj) * hf.spacing_m;
  // The target, seen from a, is lowered by the curvature drop too.
  const double bz = bz_m - curvature_coeff * d_total * d_total / (2.0 * kEarthRadiusM);
  return clear_of_lines(hf, true, ai, aj, az_m, bi, bj, bz, d_total, curvature_coeff) &&
         clear_of_lines(hf, false, ai, aj, az_m, bi, bj, bz, d_total, curvature_coeff);
}

double exact_visibility(const Heightfield& hf, const std::vector<float>& area, const FieldParams& params, int i, int j,
                        double z_m) {
  if (z_m < hf.at(i, j)) return 0.0;
  double sum_a = 0;
  for (float a : area) sum_a += a;
  const int r = params.range_posts;
  const bool cube = params.range_shape == RangeShape::cube;
  const bool sphere = params.range_shape == RangeShape::sphere;
  const double range_m = r * hf.spacing_m;
  int pi_lo = 0, pi_hi = hf.nx - 1, pj_lo = 0, pj_hi = hf.ny - 1;
  if (params.range_shape != RangeShape::none) {
    pi_lo = std::max(0, i - r);
    pi_hi = std::min(hf.nx - 1, i + r);
    pj_lo = std::max(0, j - r);
    pj_hi = std::min(hf.ny - 1, j + r);
  }
  double seen = 0;
  for (int pj = pj_lo; pj <= pj_hi; ++pj) {
    for (int pi = pi_lo; pi <= pi_hi; ++pi) {
      const std::size_t n =
          static_cast<std::size_t>(pj) * static_cast<std::size_t>(hf.nx) + static_cast<std::size_t>(pi);
      const double w = params.weights.empty() ? 1.0 : params.weights[n];
      if (w == 0) continue;
      const double ground = hf.at(pi, pj);
      const double eye = ground + params.eye_height_m;
      if (cube && (z_m < ground || z_m > ground + 2.0 * range_m)) continue;
      if (sphere) {
        const double dh = std::hypot(double(pi - i), double(pj - j)) * hf.spacing_m;
        if (dh * dh + (z_m - eye) * (z_m - eye) > range_m * range_m) continue;
      }
      if (r3_visible(hf, pi, pj, eye, i, j, z_m, params.curvature_coeff)) seen += area[n] * w;
    }
  }
  return seen / sum_a;
}

}  // namespace visvol::fields
