// Fits a path into the flight envelope: the projection that makes any path
// (a rope's, a graph search's, a user's) flyable while moving it as little as
// the limits need.
//
// 1. Points beside the planning bounds are moved onto them.
// 2. Turns (fixed-wing): interior vertices whose fillet radius is under the
//    vehicle's are pulled towards their neighbours' midpoint, in the
//    horizontal plane, until every fillet fits (a bounded number of passes).
// 3. Heights: each vertex keeps its height where it can, inside a band from
//    the clearance (and above every visible-to hull) up to the ceiling (terrain
//    + max AGL, max altitude, the field's top, and under every hidden-from
//    hull), with every segment within the climb and descent limits (a leg
//    by a corner within the share of them its fixed-wing arc leaves:
//    theta / (2 tan(theta / 2)), as the arc is shorter than the legs it
//    cuts). The band
//    is checked between vertices too (the terrain under a straight segment,
//    at samples and exactly where its height is extreme, as the checker
//    finds it: rt/rope/terrain_probe.hpp); a segment that cannot hold it is
//    split (every such segment of a pass at once). The ends stay where they
//    are.
//    Heights are chosen by two passes along the path: backwards, the band of
//    heights from which the end is still reachable; forwards, the height
//    nearest the path's own inside that band and one segment's climb or
//    descent from the previous vertex.
// 4. A split shortens the segments beside it, and with them the fillets of
//    the turns there: where a turn no longer fits, steps 2 and 3 run again
//    (a few rounds). Splits fall in the middle half of a segment.
// 5. A PX4 fixed-wing (rt::px4_flights): where its flights come under the
//    clearance (cutting a corner, or climbing behind the legs at its climb
//    rate), the legs it flies there get a higher floor, and step 3 runs
//    again (the check's "flown-clearance").
//
// The fit is exact for the envelope where the band allows it (`feasible`);
// constraint hulls come from the field's hull kernel, so hidden-from and
// visible-to are made likely, not proven: rt::PathChecker's sight lines judge.
// The hulls yield to the envelope: where a fit inside them is not feasible,
// the heights start inside them and are fitted to the envelope alone, as
// near there as it allows (an observer unmet is reported; a path the vehicle
// cannot fly is not planned for one).
// Offline: allocates.
#pragma once

#include <optional>
#include <vector>

#include "fields/heightfield.hpp"
#include "fields/volume.hpp"
#include "rt/rope/field_forces.hpp"
#include "rt/rope/vehicle.hpp"

namespace visvol::rt {

struct EnvelopeFitSpec {
  VehicleEnvelope envelope;
  std::optional<fields::Bounds2D> planning_bounds;
  double top_m = std::numeric_limits<double>::infinity();  // highest height allowed (the field's top)
  double margin_m = 0.5;  // kept inside the height limits (the checker samples elsewhere)
  // kept inside the climb and descent limits: a path written with millimetre
  // coordinates (CSV, GeoJSON) still checks as met when read back
  double angle_margin_deg = 0.1;
  // turns opened to this share over the least turn radius: the same, for
  // turns between vertices a few metres apart (a millimetre moved a tightest
  // turn from 80.3 to 79.6 m against 80)
  double turn_margin = 0.01;
  double hull_margin_m = 5.0;           // kept under hidden-from and over visible-to hulls
  double step_m = 0;                    // between-vertex samples; 0: a quarter post spacing
  std::size_t max_points = 0;           // vertices the fit may end with (it splits segments); 0: 4 n + 64
  std::vector<const PointHull*> below;  // hidden-from hulls (finest level)
  std::vector<const PointHull*> above;  // visible-to hulls
};

struct EnvelopeFit {
  std::vector<Vec3> path;
  // heights inside the band and slopes within the limits everywhere, and a
  // PX4 fixed-wing's flights over the clearance
  bool feasible = false;
};

// `terrain` is the finest terrain (bilinear between posts).
EnvelopeFit fit_to_envelope(const std::vector<Vec3>& path, const EnvelopeFitSpec& spec,
                            const fields::Heightfield& terrain);

}  // namespace visvol::rt
