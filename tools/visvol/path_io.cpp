#include "path_io.hpp"

#include <ogr_spatialref.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"

namespace visvol::cli {

namespace {

// Numbers of a line: separators are spaces, tabs and commas.
bool parse_numbers(std::string line, std::vector<double>& out) {
  for (char& c : line) {
    if (c == ',' || c == '\t' || c == ';') c = ' ';
  }
  std::istringstream in(line);
  out.clear();
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || errno == ERANGE) return false;
    out.push_back(v);
  }
  return true;
}

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

}  // namespace

Result<PathFile> read_path_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return io_error(path + ": " + std::strerror(errno));
  PathFile out;
  std::string line;
  int line_no = 0;
  int columns = 0;
  std::vector<double> v;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
    if (!parse_numbers(line, v)) {
      if (out.points.empty() && columns == 0 && line_no == 1) continue;  // a header
      return invalid_argument(path + ": line " + std::to_string(line_no) + ": '" + line +
                              "' is not numbers x y [z]");
    }
    if (v.size() != 2 && v.size() != 3) {
      return invalid_argument(path + ": line " + std::to_string(line_no) + ": " + std::to_string(v.size()) +
                              " numbers; expected x y or x y z");
    }
    if (columns == 0) columns = static_cast<int>(v.size());
    if (static_cast<int>(v.size()) != columns) {
      return invalid_argument(path + ": line " + std::to_string(line_no) + " has " + std::to_string(v.size()) +
                              " numbers, earlier lines " + std::to_string(columns));
    }
    for (double d : v) {
      if (!std::isfinite(d)) return invalid_argument(path + ": line " + std::to_string(line_no) + ": not finite");
    }
    out.points.push_back({v[0], v[1], v.size() == 3 ? v[2] : 0.0});
  }
  if (out.points.size() < 2) return invalid_argument(path + ": fewer than 2 points");
  out.has_heights = columns == 3;
  return out;
}

std::vector<Vec3> lift_polyline(const std::vector<Vec3>& points, double clearance_m, double step_m,
                                const std::function<double(double, double)>& terrain_height) {
  std::vector<Vec3> out;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    const double dx = points[i + 1].x() - points[i].x(), dy = points[i + 1].y() - points[i].y();
    const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(dx, dy) / step_m)));
    for (int k = 0; k < n; ++k) {
      const double x = points[i].x() + dx * k / n, y = points[i].y() + dy * k / n;
      out.push_back({x, y, terrain_height(x, y) + clearance_m});
    }
  }
  const Vec3& last = points.back();
  out.push_back({last.x(), last.y(), terrain_height(last.x(), last.y()) + clearance_m});
  return out;
}

Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt) {
  if (crs_wkt.empty()) return Status(Errc::unsupported, "the pack has no CRS, so there is no WGS84 position");
  OGRSpatialReference source, wgs84;
  if (source.importFromWkt(crs_wkt.c_str()) != OGRERR_NONE) return corrupt("the pack's CRS WKT does not parse");
  wgs84.SetWellKnownGeogCS("WGS84");
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&source, &wgs84));
  if (!ct) return Status(Errc::unsupported, "no transformation from the pack's CRS to WGS84");
  std::vector<Vec3> out;
  out.reserve(vertices.size());
  for (const Vec3& v : vertices) {
    double x = v.x(), y = v.y();
    if (!ct->Transform(1, &x, &y)) return invalid_argument("a path vertex cannot be converted to WGS84");
    out.push_back({x, y, v.z()});  // heights stay the DEM's (mean sea level)
  }
  return out;
}

Status write_path_outputs(const std::string& base, const PathReport& r, std::vector<std::string>& written) {
  const Result<std::vector<Vec3>> geo = to_wgs84(r.vertices, r.crs_wkt);
  // CSV: always (projected coordinates are enough)
  {
    std::ostringstream csv;
    csv << "index,x_m,y_m,z_m," << (geo.ok() ? "lon_deg,lat_deg," : "") << "fp,clearance_m\n";
    for (std::size_t i = 0; i < r.vertices.size(); ++i) {
      const Vec3& v = r.vertices[i];
      csv << i << ',' << fixed(v.x(), 3) << ',' << fixed(v.y(), 3) << ',' << fixed(v.z(), 3) << ',';
      if (geo.ok()) csv << fixed((*geo)[i].x(), 8) << ',' << fixed((*geo)[i].y(), 8) << ',';
      csv << fixed(r.per_vertex[i].fp, 6) << ',' << fixed(r.per_vertex[i].clearance_m, 2) << '\n';
    }
    VISVOL_RETURN_IF_ERROR(write_text_file(base + ".csv", csv.str()));
    written.push_back(base + ".csv");
  }
  if (!geo.ok()) return geo.status().with_context("GeoJSON, KML and .plan not written");
  const rt::PathMetrics& m = r.metrics;
  nlohmann::json props = {{"objective", r.objective},          {"model", r.model},
                          {"pack", r.pack},                    {"fc", m.fc},
                          {"length_m", m.length_m},            {"min_clearance_m", m.min_clearance_m},
                          {"max_climb_deg", m.max_climb_deg},  {"max_descent_deg", m.max_descent_deg},
                          {"min_turn_radius_m", std::isfinite(m.min_turn_radius_m) ? nlohmann::json(m.min_turn_radius_m) : nlohmann::json()},
                          {"height_reference", "the DEM's vertical datum (mean sea level)"}};
  nlohmann::json fp = nlohmann::json::array(), clearance = nlohmann::json::array();
  for (const VertexInfo& v : r.per_vertex) {
    fp.push_back(v.fp);
    clearance.push_back(v.clearance_m);
  }
  props["vertex_fp"] = fp;
  props["vertex_clearance_m"] = clearance;
  // GeoJSON
  {
    nlohmann::json coords = nlohmann::json::array();
    for (const Vec3& g : *geo) coords.push_back({g.x(), g.y(), g.z()});
    nlohmann::json gj = {{"type", "FeatureCollection"},
                         {"features", {{{"type", "Feature"},
                                        {"geometry", {{"type", "LineString"}, {"coordinates", coords}}},
                                        {"properties", props}}}}};
    VISVOL_RETURN_IF_ERROR(write_text_file(base + ".geojson", gj.dump(1) + "\n"));
    written.push_back(base + ".geojson");
  }
  // KML
  {
    std::ostringstream kml;
    kml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>visvol "
        << r.objective << " path</name>\n<Placemark>\n<name>F_c " << fixed(m.fc, 4) << ", "
        << fixed(m.length_m / 1000.0, 2) << " km, clearance " << fixed(m.min_clearance_m, 0) << " m</name>\n"
        << "<LineString>\n<altitudeMode>absolute</altitudeMode>\n<coordinates>\n";
    for (const Vec3& g : *geo) kml << fixed(g.x(), 8) << ',' << fixed(g.y(), 8) << ',' << fixed(g.z(), 2) << '\n';
    kml << "</coordinates>\n</LineString>\n</Placemark>\n</Document>\n</kml>\n";
    VISVOL_RETURN_IF_ERROR(write_text_file(base + ".kml", kml.str()));
    written.push_back(base + ".kml");
  }
  // QGroundControl .plan: waypoints (MAV_CMD_NAV_WAYPOINT, 16) in
  // MAV_FRAME_GLOBAL (0: altitude above mean sea level), QGC's absolute mode (2).
  {
    nlohmann::json items = nlohmann::json::array();
    int id = 1;
    for (const Vec3& g : *geo) {
      items.push_back({{"AMSLAltAboveTerrain", nullptr},
                       {"Altitude", g.z()},
                       {"AltitudeMode", 2},
                       {"autoContinue", true},
                       {"command", 16},
                       {"doJumpId", id++},
                       {"frame", 0},
                       {"params", {0, 0, 0, nullptr, g.y(), g.x(), g.z()}},
                       {"type", "SimpleItem"}});
    }
    const Vec3& home = geo->front();
    nlohmann::json plan = {
        {"fileType", "Plan"},
        {"geoFence", {{"circles", nlohmann::json::array()}, {"polygons", nlohmann::json::array()}, {"version", 2}}},
        {"groundStation", "QGroundControl"},
        {"mission",
         {{"cruiseSpeed", 15},
          {"firmwareType", 12},
          {"globalPlanAltitudeMode", 2},
          {"hoverSpeed", 5},
          {"items", items},
          {"plannedHomePosition", {home.y(), home.x(), home.z()}},
          {"vehicleType", 1},
          {"version", 2}}},
        {"rallyPoints", {{"points", nlohmann::json::array()}, {"version", 2}}},
        {"version", 1}};
    VISVOL_RETURN_IF_ERROR(write_text_file(base + ".plan", plan.dump(1) + "\n"));
    written.push_back(base + ".plan");
  }
  return Status::ok_status();
}

}  // namespace visvol::cli
