// Tolerances every layer judges positions by, one way.
#pragma once

namespace visvol {

// Positions against the planning bounds compare to a centimetre on each axis,
// as heights do: a path on their edge, written to a file and read back
// (millimetres, or WGS84 degrees through PROJ), or a bound printed to the
// centimetre and typed back, moves by less, out as often as in.
inline constexpr double kBoundsTolM = 0.01;

}  // namespace visvol
