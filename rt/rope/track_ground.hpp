// The highest terrain under a path's track over a stretch of it: the ground
// an aircraft that takes its heights early flies over.
//
// A fixed-wing's autopilot takes the next waypoint, and the height it climbs
// or descends to, at its switch distance R before the waypoint it flies to
// (PX4's L1 or NPFG switch distance, about 95 m at 20 m/s and more in a
// tailwind: rt::switch_distance_m; ArduPlane's WP_RADIUS). PX4 ramps its altitude target over the leg less H (its
// first-order hold; H = rt::altitude_hold_m, R and at least its loiter
// radius), so it flies each planned height up to H early; on a leg no
// longer than H it holds no ramp and steps to the leg's end height where it
// takes that waypoint, R before the leg's start. ArduPlane ramps over the
// whole leg. An independent simulation of PX4 flying visvol's missions
// crossed a crest 14.8 m over it where the plan had 31 m: the descent after
// the crest began a leg early. A path keeps its clearance flown either way
// where the height at every point clears the highest ground under the H
// metres of track behind it, and on every leg no longer than H the lower of
// its two heights clears the highest ground of the leg's held stretch
// (held_stretch below; rt::PathChecker's "early-descent"). (PX4 before 1.14
// with MIS_ALTMODE 0 steps on every leg: not modelled.)
//
// Positions along the track are horizontal distances from the first vertex,
// m. The terrain is bilinear: along a straight leg it is one quadratic between
// the grid lines crossed, so its highest over any stretch lies at the
// stretch's ends, a grid line or a quadratic's vertex (the points
// rt::for_each_terrain_probe gives): exact, whatever the sampling.
// Offline: allocates. Keeps a pointer to the terrain, which must outlive it.
#pragma once

#include <vector>

#include "fields/heightfield.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt {

class TrackGround {
 public:
  // The track of `count` vertices (their heights are not used); legs with a
  // coordinate that is not finite add no ground.
  TrackGround(const fields::Heightfield& terrain, const Vec3* v, int count);

  double length_m() const { return vertex_m_.empty() ? 0.0 : vertex_m_.back(); }
  // Horizontal distance along the track to vertex k.
  double at_vertex_m(int k) const { return vertex_m_[static_cast<std::size_t>(k)]; }
  // The highest terrain under the track from `from_m` to `to_m` along it
  // (clamped to the track; the ground at `to_m` when from_m >= to_m).
  double highest_m(double from_m, double to_m) const;

  // The stretch of track (m along it) over which an autopilot with
  // acceptance radius `radius_m` flies between the heights of vertices
  // `first` and `last` (a leg, or the leg a thinning makes of the vertices
  // between): from `radius_m` before `first`, where it takes `last` as its
  // waypoint, to `radius_m` before `last`, where it takes the one after (on
  // the last leg, the mission's next item: the end's own height). The legs'
  // stretches tile the track up to `radius_m` before its end. Clamped to the
  // track: empty (to_m <= from_m) where it lies wholly before the start.
  struct Stretch {
    double from_m = 0, to_m = 0;
    bool empty() const { return !(to_m > from_m); }
    double length_m() const { return empty() ? 0.0 : to_m - from_m; }
  };
  Stretch held_stretch(int first, int last, double radius_m) const;
  // The least height over the ground on that stretch of an aircraft going
  // from `first_z_m` to `last_z_m`: descending, no lower than `last_z_m` on
  // all of it; climbing (or level), no lower than `first_z_m` up to `first`
  // (past it the plan's own heights, which it climbs to no later than
  // planned, starting the radius early). +infinity where that is empty.
  double held_clearance_m(int first, int last, double first_z_m, double last_z_m, double radius_m) const;
  // The same for a leg between two points `first_m` and `last_m` along the
  // track (a point the envelope fit splits a leg at lies on it).
  Stretch held_stretch_at(double first_m, double last_m, double radius_m) const;
  double held_clearance_at_m(double first_m, double last_m, double first_z_m, double last_z_m, double radius_m) const;

 private:
  double ground_at(double along_m) const;
  double highest_breakpoint(std::size_t first, std::size_t end) const;  // over [first, end)

  const fields::Heightfield* terrain_;
  std::vector<Vec3> track_;
  std::vector<double> vertex_m_;
  std::vector<double> at_m_;  // breakpoints in order along the track
  // a segment tree over the breakpoints' ground: leaves at [n, 2n), each
  // node the highest of its two children (linear memory: a check's path may
  // hold millions of vertices)
  std::vector<double> most_;
};

}  // namespace visvol::rt
