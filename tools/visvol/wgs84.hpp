// Positions and heights between a pack's CRS and WGS84, through PROJ: the
// pack's projected x, y to longitude and latitude (at each point the most
// accurate transformation installed, and how coarse the coarsest was), and
// EGM96 orthometric heights to WGS84 ellipsoidal ones. What the path files
// (path_io.hpp) read and write.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::cli {

using rt::Vec3;

// How positions went between the pack's CRS and WGS84: the coarsest of the
// transformations PROJ applied (at each point the most accurate one whose
// area holds it and whose grids are installed) and its accuracy, m (0: a
// change of projection only; negative: not known).
struct Wgs84Conversion {
  std::string operation;
  double accuracy_m = 0;
  std::string describe() const;  // "NAD27 to WGS 84 (6) ... (accurate to 7 m by EPSG)"
};
// Coarser than this, the outputs and the operator are told.
inline constexpr double kTrustedWgs84AccuracyM = 1.0;
// A line for the operator when `c` is coarser than kTrustedWgs84AccuracyM or
// not known; "" otherwise.
std::string wgs84_accuracy_note(const Wgs84Conversion& c);

// Whether a CRS is one plans convert to WGS84: projected, in metres, as a
// pack's grid is; nothing where its WKT does not parse.
std::optional<bool> projected_in_metres(const std::string& crs_wkt);

// WGS84 (longitude, latitude, height) of the vertices, or an error when the
// pack has no CRS to convert from. Heights are kept.
Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt,
                                   Wgs84Conversion* conversion = nullptr);
// The reverse: WGS84 (longitude, latitude, height) to the pack's CRS; heights
// are kept. An error when there is no CRS or a point does not convert.
Result<std::vector<Vec3>> from_wgs84(const std::vector<Vec3>& lon_lat_h, const std::string& crs_wkt,
                                     Wgs84Conversion* conversion = nullptr);

// Heights at WGS84 (longitude, latitude, height) points: EGM96 orthometric to
// WGS84 ellipsoidal (h = H + N) and back, through PROJ with the EGM96 grid
// (no network, no ballpark "no shift" fallback). Longitudes and latitudes are
// kept. Errc::unsupported naming the grid when it is not installed.
Result<std::vector<Vec3>> orthometric_to_ellipsoidal(const std::vector<Vec3>& lon_lat_h);
Result<std::vector<Vec3>> ellipsoidal_to_orthometric(const std::vector<Vec3>& lon_lat_h);
// Either of the two, with the grid PROJ used (for the files that name it).
struct GeoidShift {
  std::vector<Vec3> points;
  std::string grid;
};
Result<GeoidShift> shift_heights(const std::vector<Vec3>& lon_lat_h, bool to_ellipsoidal);

}  // namespace visvol::cli
