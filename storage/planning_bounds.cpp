#include "storage/planning_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace visvol::storage {

fields::Bounds2D post_extent(const fields::VolumeGeometry& level) {
  // post (0, 0) is the north-west post; x grows east, y shrinks south
  fields::Bounds2D b;
  b.xmin_m = level.origin_x;
  b.xmax_m = level.origin_x + (level.nx - 1) * level.spacing_m;
  b.ymax_m = level.origin_y;
  b.ymin_m = level.origin_y - (level.ny - 1) * level.spacing_m;
  return b;
}

double planning_margin_m(const fields::VolumeGeometry& finest, fields::RangeShape shape, int range_posts,
                         std::optional<double> margin_override_m) {
  if (margin_override_m) return *margin_override_m;
  if (shape != fields::RangeShape::none) return range_posts * finest.spacing_m;
  const fields::Bounds2D extent = post_extent(finest);
  const double smaller_side_m = std::min(extent.xmax_m - extent.xmin_m, extent.ymax_m - extent.ymin_m);
  return smaller_side_m / kUnrangedMarginDivisor;
}

fields::Bounds2D inset_post_extent(const fields::VolumeGeometry& finest, double margin_m) {
  fields::Bounds2D b = post_extent(finest);
  b.xmin_m += margin_m;
  b.ymin_m += margin_m;
  b.xmax_m -= margin_m;
  b.ymax_m -= margin_m;
  return b;
}

PlanningBounds planning_bounds_rule(const fields::VolumeGeometry& finest, fields::RangeShape shape, int range_posts,
                                    std::optional<double> margin_override_m) {
  PlanningBounds p;
  p.margin_m = planning_margin_m(finest, shape, range_posts, margin_override_m);
  p.box = inset_post_extent(finest, p.margin_m);
  return p;
}

std::string describe(const fields::Bounds2D& box) { return fields::describe_inward(box); }

std::string describe(const PlanningBounds& bounds) {
  const double m = bounds.margin_m;
  char margin[64];
  const int decimals = std::fabs(m - std::round(m)) < 0.005 ? 0 : 2;
  std::snprintf(margin, sizeof margin, " (margin %.*f m)", decimals, m);
  return describe(bounds.box) + margin;
}

nlohmann::json planning_json(const PlanningBounds& bounds) {
  return {{"xmin_m", bounds.box.xmin_m},
          {"ymin_m", bounds.box.ymin_m},
          {"xmax_m", bounds.box.xmax_m},
          {"ymax_m", bounds.box.ymax_m},
          {"margin_m", bounds.margin_m}};
}

}  // namespace visvol::storage
