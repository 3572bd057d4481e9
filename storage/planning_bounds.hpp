// Planning bounds: the trusted region of a field pack.
//
// F_p near a DEM's border undercounts the observers that stand beyond it, so
// paths are planned inside the finest level's post extent less a margin on
// every side. The margin is, unless given explicitly, the finest level's range
// in metres (range_posts x spacing) for the cube and sphere ranges, and an
// eighth of the post extent's smaller side for RangeShape::none.
//
// One rule for the pack writer (which records the bounds in the metadata) and
// the reader (which derives them for packs built before they were recorded).
// Pure arithmetic: no I/O, no allocation; thread-safe.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "fields/field_params.hpp"
#include "fields/volume.hpp"

namespace visvol::storage {

struct PlanningBounds {
  fields::Bounds2D box;   // world metres in the pack's CRS, edges included
  double margin_m = 0;    // what the box leaves of the post extent on every side
  bool recorded = false;  // read from the pack's metadata (false: derived by the rule)
};

// The divisor of the post extent's smaller side for RangeShape::none.
inline constexpr double kUnrangedMarginDivisor = 8.0;

// The margin the rule uses: `margin_override_m` when given, else the range in
// metres (cube, sphere), else the smaller side of the post extent / 8 (none).
double planning_margin_m(const fields::VolumeGeometry& finest, fields::RangeShape shape, int range_posts,
                         std::optional<double> margin_override_m = std::nullopt);

// The finest level's post extent less `margin_m` on every side. Empty (see
// Bounds2D::empty) when the margin leaves nothing of the grid.
fields::Bounds2D inset_post_extent(const fields::VolumeGeometry& finest, double margin_m);

// Both of the above: the planning bounds of a pack whose finest level is `finest`.
PlanningBounds planning_bounds_rule(const fields::VolumeGeometry& finest, fields::RangeShape shape, int range_posts,
                                    std::optional<double> margin_override_m = std::nullopt);

// The post extent of a level: x from the west to the east post, y from the
// south to the north post, metres.
fields::Bounds2D post_extent(const fields::VolumeGeometry& level);

// "x 550230.00..550920.00, y 4181610.00..4182510.00" for messages and `visvol info`.
std::string describe(const fields::Bounds2D& box);
// The same and "(margin 240 m)", the margin to the centimetre when not whole metres.
std::string describe(const PlanningBounds& bounds);

// The box and its margin as a pack's metadata records them (xmin_m, ymin_m,
// xmax_m, ymax_m, margin_m): the metadata, and the summaries that show them.
nlohmann::json planning_json(const PlanningBounds& bounds);

}  // namespace visvol::storage
