// Paths in and out of `visvol plan`.
//
// In: a text file of points "x y" (lifted to the clearance above the terrain,
// densely, as the paper's tracing tool does) or "x y z", in the pack's CRS;
// separators are spaces, tabs or commas; '#' starts a comment; a first line
// that is not numbers is a header.
// Out: GeoJSON (RFC 7946: WGS84 longitude, latitude, height), CSV (pack CRS and
// WGS84, per-vertex F_p and clearance), KML (absolute altitudes) and a
// QGroundControl .plan mission (waypoints in WGS84 with altitudes above mean
// sea level: the DEM's heights). Heights are the DEM's (its vertical datum,
// normally mean sea level).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rt/base/status.hpp"
#include "rt/rope/path_metrics.hpp"

namespace visvol::cli {

using rt::Vec3;

struct PathFile {
  std::vector<Vec3> points;
  bool has_heights = false;  // 3 columns
};
Result<PathFile> read_path_file(const std::string& path);

// A 2D polyline lifted to `clearance_m` above the terrain, sampled every `step_m`.
std::vector<Vec3> lift_polyline(const std::vector<Vec3>& points_2d, double clearance_m, double step_m,
                                const std::function<double(double, double)>& terrain_height);

struct VertexInfo {
  double fp = 0;           // F_p at the vertex
  double clearance_m = 0;  // height above the terrain
};

struct PathReport {
  std::vector<Vec3> vertices;         // pack CRS, metres
  std::vector<VertexInfo> per_vertex;
  rt::PathMetrics metrics;
  std::string objective, model, pack, crs_wkt;
};

// WGS84 (longitude, latitude, height) of the vertices, or an error when the
// pack has no CRS to convert from.
Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt);

// Writes BASE.geojson, BASE.csv, BASE.kml and BASE.plan (each whole or not at
// all); `written` lists them. Without a CRS only the CSV is written and the
// status says why the others are not.
Status write_path_outputs(const std::string& base, const PathReport& report,
                          std::vector<std::string>& written);

}  // namespace visvol::cli
