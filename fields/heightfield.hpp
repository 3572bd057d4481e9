// Heightfield: the terrain as a regular grid of posts.
//
// Post (i, j) sits at the centre of DEM pixel (i, j) (GDAL's pixel-is-area
// convention): world x = origin_x + i * spacing_m (east), world y = origin_y -
// j * spacing_m (north up, row 0 is the northern edge). Heights are metres above
// the CRS's vertical datum. Horizontal spacing is metres and equal in x and y.
//
// Thread-safety: a plain value; concurrent reads are safe.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "base/status.hpp"

namespace visvol::fields {

// Grids larger than this many posts a side are refused before any allocation.
inline constexpr int kMaxPostsPerSide = 1 << 15;

struct Heightfield {
  int nx = 0;                   // posts west to east
  int ny = 0;                   // posts north to south
  double spacing_m = 0;         // distance between neighbouring posts
  double origin_x = 0;          // world x of post (0, 0), the north-west post
  double origin_y = 0;          // world y of post (0, 0)
  std::string crs_wkt;          // horizontal CRS, empty for a local metric frame
  std::vector<float> height_m;  // ny rows of nx posts, row-major

  std::size_t size() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }
  float at(int i, int j) const {
    return height_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)];
  }
  float& at(int i, int j) {
    return height_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)];
  }
  // World coordinates of post (i, j).
  double x_of(double i) const { return origin_x + i * spacing_m; }
  double y_of(double j) const { return origin_y - j * spacing_m; }
  // Grid coordinates (fractional posts) of a world point.
  double i_of(double x) const { return (x - origin_x) / spacing_m; }
  double j_of(double y) const { return (origin_y - y) / spacing_m; }
};

// Checks sizes, spacing and that every post is a finite height. `name` is the
// input's name for the message ("dem.tif").
Status validate(const Heightfield& hf, const std::string& name);

// Lowest and highest post.
struct HeightRange {
  float min_m = 0;
  float max_m = 0;
};
HeightRange height_range(const Heightfield& hf);

// Area factor A = sqrt(1 + Tx^2 + Ty^2) per post, with Tx, Ty by central
// differences (one-sided on the border). Dimensionless, >= 1.
std::vector<float> area_factor(const Heightfield& hf);

// The next coarser level of detail: each coarse post is the mean of a 2x2 block
// of fine posts and sits at the block's centre; spacing doubles. An odd last
// row or column is dropped. Requires nx >= 4 and ny >= 4.
Heightfield downsample2(const Heightfield& hf);

// Bilinear terrain height at grid coordinates (clamped to the grid).
double bilinear_height(const Heightfield& hf, double i, double j);

}  // namespace visvol::fields
