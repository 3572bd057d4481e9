#include "fields/field_params.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fields/hull_kernel.hpp"

namespace visvol::fields {

const char* to_string(RangeShape shape) {
  switch (shape) {
    case RangeShape::none: return "none";
    case RangeShape::cube: return "cube";
    case RangeShape::sphere: return "sphere";
  }
  return "unknown";
}

Result<RangeShape> parse_range_shape(const std::string& text) {
  if (text == "none") return RangeShape::none;
  if (text == "cube") return RangeShape::cube;
  if (text == "sphere") return RangeShape::sphere;
  return invalid_argument("range shape '" + text + "' is not one of none, cube, sphere");
}

Status validate(const FieldParams& p, const Heightfield& hf) {
  std::ostringstream msg;
  if (p.nz < 2 || p.nz > kMaxHeightLevels) {
    msg << "levels: " << p.nz << " is outside 2.." << kMaxHeightLevels;
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(p.ceiling_m) || p.ceiling_m < 0 || p.ceiling_m > 1.0e5) {
    msg << "ceiling: " << p.ceiling_m << " m is outside 0..100000 m";
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(p.eye_height_m) || p.eye_height_m < 0 || p.eye_height_m > 1.0e4) {
    msg << "eye height: " << p.eye_height_m << " m is outside 0..10000 m";
    return invalid_argument(msg.str());
  }
  if (p.range_shape != RangeShape::none && (p.range_posts < 1 || p.range_posts > kMaxPostsPerSide)) {
    msg << "range: " << p.range_posts << " posts is outside 1.." << kMaxPostsPerSide;
    return invalid_argument(msg.str());
  }
  if (!std::isfinite(p.curvature_coeff) || p.curvature_coeff < 0 || p.curvature_coeff > 1) {
    msg << "curvature coefficient: " << p.curvature_coeff << " is outside 0..1";
    return invalid_argument(msg.str());
  }
  if (p.exact_rings < 1 || p.exact_rings > 256) {
    msg << "exact rings: " << p.exact_rings << " is outside 1..256";
    return invalid_argument(msg.str());
  }
  if (p.threads < 0 || p.threads > 1024) {
    msg << "threads: " << p.threads << " is outside 0..1024";
    return invalid_argument(msg.str());
  }
  // Bounded so that the limit in bytes fits a size_t (1e308 MiB once became 0 bytes).
  if (!std::isfinite(p.max_memory_mib) || p.max_memory_mib <= 0 || p.max_memory_mib > kMaxMemoryMib) {
    msg << "memory limit: " << p.max_memory_mib << " MiB is outside 0.." << static_cast<long long>(kMaxMemoryMib)
        << " MiB (16 TiB), 0 excluded";
    return invalid_argument(msg.str());
  }
  if (p.vertical && !(std::isfinite(p.vertical->z0_m) && std::isfinite(p.vertical->dz_m) && p.vertical->dz_m > 0)) {
    msg << "vertical grid: level 0 at " << p.vertical->z0_m << " m, spacing " << p.vertical->dz_m
        << " m must be finite with a positive spacing";
    return invalid_argument(msg.str());
  }
  if (!p.weights.empty()) {
    if (p.weights.size() != hf.size()) {
      msg << "weights: " << p.weights.size() << " values for " << hf.nx << " x " << hf.ny << " posts";
      return invalid_argument(msg.str());
    }
    for (std::size_t n = 0; n < p.weights.size(); ++n) {
      const float w = p.weights[n];
      if (!(w >= 0.0f && w <= 1.0f)) {
        msg << "weights: post (" << n % static_cast<std::size_t>(hf.nx) << ", " << n / static_cast<std::size_t>(hf.nx)
            << ") has weight " << w << "; weights must be in [0, 1]";
        return invalid_argument(msg.str());
      }
    }
  }
  return Status::ok_status();
}

VolumeGeometry volume_geometry(const Heightfield& hf, const FieldParams& params) {
  const HeightRange hr = height_range(hf);
  VolumeGeometry g;
  g.nx = hf.nx;
  g.ny = hf.ny;
  g.nz = params.nz;
  g.spacing_m = hf.spacing_m;
  g.origin_x = hf.origin_x;
  g.origin_y = hf.origin_y;
  if (params.vertical) {
    g.z0_m = params.vertical->z0_m;
    g.dz_m = params.vertical->dz_m;
    return g;
  }
  g.z0_m = hr.min_m;
  const double span = static_cast<double>(hr.max_m) - hr.min_m + params.ceiling_m;
  // A perfectly flat grid with no ceiling still needs a positive level spacing.
  g.dz_m = std::max(span, 1.0) / (params.nz - 1);
  return g;
}

int hull_radius_posts(const FieldParams& params, const Heightfield& hf) {
  if (params.range_shape == RangeShape::none) return std::max(hf.nx, hf.ny) - 1;
  return std::min(params.range_posts, std::max(hf.nx, hf.ny) - 1);
}

}  // namespace visvol::fields
