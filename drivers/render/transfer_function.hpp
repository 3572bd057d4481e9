// The transfer function: F_p -> colour and opacity, piecewise linear between
// control points. Its colour ramp is also the picture's colour map (terrain,
// path, colour bar), so one file changes every F_p colour in a thumbnail.
//
// F is F_p as a fraction of the top of the colour scale (the renderer's
// fp_max: by default the field's largest F_p), so one transfer function suits
// any pack.
//
// File format (text, one control point per line, '#' starts a comment):
//   colour  F  R G B     F in [0, 1]; R, G, B in [0, 1]  ("color" also works)
//   opacity F  A         A in [0, 1]: the opacity a ray collects across one
//                        hundredth of the volume's largest horizontal side
// F strictly increasing within each kind; at least one point of each kind and
// at most kMaxTransferPoints; before the first point and after the last the
// end values hold.
//
// Pure values and functions: no GL, thread-safe, parsing allocates (start-up).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.hpp"

namespace visvol::render {

inline constexpr std::size_t kMaxTransferPoints = 64;  // per kind

struct ColourPoint {
  double fp;       // F_p / fp_max, in [0, 1]
  double r, g, b;  // linear components in [0, 1] (written to 8-bit sRGB PNGs as they are)
};

struct OpacityPoint {
  double fp;
  double opacity;  // in [0, 1] across kOpacityUnitFraction of the volume's largest side
};

// The length a ray must cross to collect an OpacityPoint's opacity, as a
// fraction of the volume's largest horizontal side (so a transfer function
// reads the same on a 1 km and a 100 km terrain, at any level of detail).
inline constexpr double kOpacityUnitFraction = 0.01;

struct TransferFunction {
  std::vector<ColourPoint> colour;    // sorted by fp, strictly increasing
  std::vector<OpacityPoint> opacity;  // sorted by fp, strictly increasing
};

struct Rgb {
  double r, g, b;
};

// Red (hidden) through pale yellow to blue (seen), as in the paper's Fig. 7;
// opacity falls from the hidden air (a red fog in valleys and behind ridges)
// to none for the best-seen air.
TransferFunction default_transfer_function();

// Checks counts, ranges and ordering; `name` prefixes the message.
Status validate(const TransferFunction& tf, const std::string& name);

// Parses the file format above. `name` (the file) prefixes every message,
// with the line number: "tf.txt: line 3: opacity 1.5 is outside [0, 1]".
Result<TransferFunction> parse_transfer_function(std::string_view text, const std::string& name);
Result<TransferFunction> read_transfer_function(const std::string& path);

// Interpolated colour and opacity at fp (clamped to the end points). O(points).
Rgb colour_at(const TransferFunction& tf, double fp);
double opacity_at(const TransferFunction& tf, double fp);

// Opacity over a ray segment `step_units` long, where a unit is the length
// OpacityPoint::opacity refers to: 1 - (1 - a)^step_units.
double opacity_for_step(double opacity_per_unit, double step_units);

}  // namespace visvol::render
