// The exact reference: Franklin & Ray's R3 sight line.
//
// The open segment from a to b is tested wherever it crosses a grid line, with
// the terrain interpolated linearly along that grid line; a and b see each other
// when the segment is strictly above the terrain at every crossing. Curvature
// and refraction lower every point d metres from `a` by coeff * d^2 / (2 R).
//
// Cost: O(|b - a| in posts) per sight line, so O(r^2) per voxel: for tests and
// small grids, not for whole fields.
#pragma once

#include <vector>

#include "fields/field_params.hpp"
#include "fields/heightfield.hpp"
#include "fields/volume.hpp"

namespace visvol::fields {

// a and b in grid coordinates (posts) and metres of height, anywhere: the
// sight line is judged over the grid lines it crosses (beyond the grid, the
// terrain is unknown and blocks nothing); a coordinate that is not finite is
// never visible.
bool r3_visible(const Heightfield& hf, double ai, double aj, double az_m, double bi, double bj, double bz_m,
                double curvature_coeff);

// F_p at the point above post (i, j) at height z_m, by the paper's definition
// with R3 visibility, the range of `params`, and the area factor `area`.
// 0 below the terrain.
double exact_visibility(const Heightfield& hf, const std::vector<float>& area, const FieldParams& params, int i, int j,
                        double z_m);

}  // namespace visvol::fields
