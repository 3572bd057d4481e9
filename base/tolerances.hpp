// Tolerances every layer judges positions by, one way.
#pragma once

#include <cmath>

namespace visvol {

// Positions against the planning bounds compare to a centimetre on each axis,
// as heights do: a path on their edge, written to a file and read back
// (millimetres, or WGS84 degrees through PROJ), or a bound printed to the
// centimetre and typed back, moves by less, out as often as in.
inline constexpr double kBoundsTolM = 0.01;

// Heights (a point against the terrain or under a ceiling) compare to a
// centimetre, as positions against the planning bounds do.
inline constexpr double kHeightTolM = 0.01;

// Two points within a centimetre are one: an observer named both hidden-from
// and visible-to (no path meets both) is refused by the planner's check, the
// console's options and the DDS codec alike, by this one test.
inline constexpr double kSamePointM = 0.01;
inline bool same_point(double ax_m, double ay_m, double az_m, double bx_m, double by_m, double bz_m) {
  return std::hypot(ax_m - bx_m, ay_m - by_m, az_m - bz_m) < kSamePointM;
}

}  // namespace visvol
