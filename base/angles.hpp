// Angle constants every layer converts by, one definition (radians and
// degrees).
#pragma once

namespace visvol {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegPerRad = 180.0 / kPi;
inline constexpr double kRadPerDeg = kPi / 180.0;

}  // namespace visvol
