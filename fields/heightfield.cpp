#include "fields/heightfield.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace visvol::fields {

Status validate(const Heightfield& hf, const std::string& name) {
  std::ostringstream msg;
  if (hf.nx < 2 || hf.ny < 2) {
    msg << name << ": grid is " << hf.nx << " x " << hf.ny << " posts; at least 2 x 2 are needed";
    return invalid_argument(msg.str());
  }
  if (hf.nx > kMaxPostsPerSide || hf.ny > kMaxPostsPerSide) {
    msg << name << ": grid is " << hf.nx << " x " << hf.ny << " posts; at most " << kMaxPostsPerSide
        << " a side are supported (crop or resample it)";
    return invalid_argument(msg.str());
  }
  if (!(std::isfinite(hf.spacing_m) && hf.spacing_m > 0)) {
    msg << name << ": post spacing " << hf.spacing_m << " m must be positive and finite";
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(hf.origin_x) || !std::isfinite(hf.origin_y)) {
    msg << name << ": origin (" << hf.origin_x << ", " << hf.origin_y << ") is not finite";
    return invalid_argument(msg.str());
  }
  if (hf.height_m.size() != hf.size()) {
    msg << name << ": " << hf.height_m.size() << " heights for " << hf.nx << " x " << hf.ny << " posts";
    return invalid_argument(msg.str());
  }
  for (int j = 0; j < hf.ny; ++j) {
    for (int i = 0; i < hf.nx; ++i) {
      const float h = hf.at(i, j);
      // Heights beyond +-20 km are not terrain on Earth: a nodata value leaked through.
      if (!std::isfinite(h) || std::fabs(h) > 2.0e4f) {
        msg << name << ": post (" << i << ", " << j << ") has height " << h
            << " m (NaN, nodata or not terrain); fill or crop it";
        return invalid_argument(msg.str());
      }
    }
  }
  return Status::ok_status();
}

HeightRange height_range(const Heightfield& hf) {
  const auto mm = std::minmax_element(hf.height_m.begin(), hf.height_m.end());
  return {*mm.first, *mm.second};
}

std::vector<float> area_factor(const Heightfield& hf) {
  std::vector<float> a(hf.size());
  for (int j = 0; j < hf.ny; ++j) {
    const int j0 = std::max(j - 1, 0);
    const int j1 = std::min(j + 1, hf.ny - 1);
    for (int i = 0; i < hf.nx; ++i) {
      const int i0 = std::max(i - 1, 0);
      const int i1 = std::min(i + 1, hf.nx - 1);
      const double tx = (static_cast<double>(hf.at(i1, j)) - hf.at(i0, j)) / ((i1 - i0) * hf.spacing_m);
      const double ty = (static_cast<double>(hf.at(i, j1)) - hf.at(i, j0)) / ((j1 - j0) * hf.spacing_m);
      a[static_cast<std::size_t>(j) * static_cast<std::size_t>(hf.nx) + static_cast<std::size_t>(i)] =
          static_cast<float>(std::sqrt(1.0 + tx * tx + ty * ty));
    }
  }
  return a;
}

Heightfield downsample2(const Heightfield& hf) {
  Heightfield c;
  c.nx = hf.nx / 2;
  c.ny = hf.ny / 2;
  c.spacing_m = hf.spacing_m * 2;
  // The coarse post is the centre of the 2x2 block of fine posts.
  c.origin_x = hf.origin_x + 0.5 * hf.spacing_m;
  c.origin_y = hf.origin_y - 0.5 * hf.spacing_m;
  c.crs_wkt = hf.crs_wkt;
  c.height_m.resize(c.size());
  for (int j = 0; j < c.ny; ++j) {
    for (int i = 0; i < c.nx; ++i) {
      const double s = static_cast<double>(hf.at(2 * i, 2 * j)) + hf.at(2 * i + 1, 2 * j) + hf.at(2 * i, 2 * j + 1) +
                       hf.at(2 * i + 1, 2 * j + 1);
      c.at(i, j) = static_cast<float>(s * 0.25);
    }
  }
  return c;
}

double bilinear_height(const Heightfield& hf, double i, double j) {
  i = std::clamp(i, 0.0, static_cast<double>(hf.nx - 1));
  j = std::clamp(j, 0.0, static_cast<double>(hf.ny - 1));
  const int i0 = std::min(static_cast<int>(i), hf.nx - 2);
  const int j0 = std::min(static_cast<int>(j), hf.ny - 2);
  const double fi = i - i0;
  const double fj = j - j0;
  const double h00 = hf.at(i0, j0), h10 = hf.at(i0 + 1, j0);
  const double h01 = hf.at(i0, j0 + 1), h11 = hf.at(i0 + 1, j0 + 1);
  return (1 - fj) * ((1 - fi) * h00 + fi * h10) + fj * ((1 - fi) * h01 + fi * h11);
}

}  // namespace visvol::fields
