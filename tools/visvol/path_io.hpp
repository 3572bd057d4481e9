// Paths in and out of `visvol plan` (and into `visvol render`).
//
// In (read_path_file), three formats told apart by their content:
//   - text: points "x y" (lifted to the clearance above the terrain, densely,
//     as the paper's tracing tool does) or "x y z", in the pack's CRS;
//     separators are spaces, tabs or commas; '#' starts a comment; a first
//     line that is not numbers is a header;
//   - the CSV `visvol plan` writes: a header naming x_m, y_m and z_m (pack
//     CRS, metres) and optionally fp; other columns are ignored;
//   - the GeoJSON `visvol plan` writes: one LineString (bare, in a Feature or
//     in a FeatureCollection), RFC 7946 WGS84 longitude, latitude and optional
//     height, converted to the pack's CRS with OGR (the reverse of the
//     writer); heights stay the DEM's. Its properties.vertex_fp, when
//     present, is the F_p of each vertex.
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

enum class PathFormat { text, plan_csv, geojson };

struct PathFile {
  std::vector<Vec3> points;  // pack CRS, metres (z: the DEM's datum, 0 without heights)
  bool has_heights = false;  // every point has a z
  std::vector<double> fp;    // F_p per point from the file (plan CSV, GeoJSON), or empty
  PathFormat format = PathFormat::text;
};
// At least 2 points, all finite. crs_wkt is the pack's CRS: a GeoJSON path
// needs it (an error names the file otherwise); the other formats ignore it.
// Errors name the file and the line (or the JSON member) and the problem.
Result<PathFile> read_path_file(const std::string& path, const std::string& crs_wkt = {});

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
// The reverse: WGS84 (longitude, latitude, height) to the pack's CRS; heights
// are kept. An error when there is no CRS or a point does not convert.
Result<std::vector<Vec3>> from_wgs84(const std::vector<Vec3>& lon_lat_h, const std::string& crs_wkt);

// Writes BASE.geojson, BASE.csv, BASE.kml and BASE.plan (each whole or not at
// all); `written` lists them. Without a CRS only the CSV is written and the
// status says why the others are not.
Status write_path_outputs(const std::string& base, const PathReport& report,
                          std::vector<std::string>& written);

}  // namespace visvol::cli
