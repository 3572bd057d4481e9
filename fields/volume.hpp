// The voxel grid above a heightfield and a dense volume of values on it.
//
// Voxel (i, j, k) sits above post (i, j) at height z0_m + k * dz_m. Levels are
// uniform in absolute height from the lowest post to the highest post plus a
// ceiling. Values are stored x fastest, then y, then z:
//   index = (k * ny + j) * nx + i.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace visvol::fields {

struct VolumeGeometry {
  int nx = 0, ny = 0, nz = 0;
  double spacing_m = 0;  // horizontal voxel size, equal to the post spacing
  double origin_x = 0;   // world x of voxel column (0, 0), the north-west post
  double origin_y = 0;   // world y of voxel column (0, 0)
  double z0_m = 0;       // height of level 0 (the lowest post)
  double dz_m = 0;       // height between levels

  std::size_t voxel_count() const {
    return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz);
  }
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(ny) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(i);
  }
  double z_of(int k) const { return z0_m + k * dz_m; }
  double top_m() const { return z0_m + (nz - 1) * dz_m; }
};

// A horizontal box in world metres (the pack's CRS), edges included.
struct Bounds2D {
  double xmin_m = 0, ymin_m = 0, xmax_m = 0, ymax_m = 0;

  bool contains(double x_m, double y_m) const {
    return x_m >= xmin_m && x_m <= xmax_m && y_m >= ymin_m && y_m <= ymax_m;
  }
  bool empty() const { return !(xmax_m > xmin_m && ymax_m > ymin_m); }
};

// "x XMIN..XMAX, y YMIN..YMAX" in metres to the centimetre, rounded inward:
// a point typed back from the text is inside (452918.0723 printed as
// 452918.07 was refused as --to). Every message that names bounds says it so.
inline std::string describe_inward(const Bounds2D& box) {
  auto up = [](double v) { return std::ceil(v * 100.0 - 1e-6) / 100.0; };
  auto down = [](double v) { return std::floor(v * 100.0 + 1e-6) / 100.0; };
  char text[128];
  std::snprintf(text, sizeof text, "x %.2f..%.2f, y %.2f..%.2f", up(box.xmin_m), down(box.xmax_m), up(box.ymin_m),
                down(box.ymax_m));
  return text;
}

// A dense volume of float values (F_p in [0, 1] for the visibility field).
struct DenseVolume {
  VolumeGeometry geometry;
  std::vector<float> values;  // geometry.voxel_count() values

  float at(int i, int j, int k) const { return values[geometry.index(i, j, k)]; }
};

}  // namespace visvol::fields
