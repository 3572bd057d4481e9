#include "path_io.hpp"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "cli.hpp"

namespace visvol::cli {

namespace {

// Path files are small (a 100000-segment plan's GeoJSON is under 20 MiB):
// anything larger is not a path.
constexpr std::uintmax_t kMaxPathFileBytes = 64u << 20;
// Characters of a bad line quoted in a message.
constexpr std::size_t kQuotedChars = 40;

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

// A line for a message: at most kQuotedChars, unprintable bytes as '?', so a
// binary file does not spill onto the terminal.
std::string quoted(const std::string& line) {
  std::string out;
  for (char c : line.substr(0, kQuotedChars)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  if (line.size() > kQuotedChars) out += "...";
  return out;
}

Result<std::string> read_whole_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return io_error(path + ": is a folder, not a path file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return io_error(path + ": " + std::strerror(errno));
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxPathFileBytes) {
    return invalid_argument(path + ": " + std::to_string(size >> 20) + " MiB is too large for a path file (at most " +
                            std::to_string(kMaxPathFileBytes >> 20) + " MiB)");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return io_error(path + ": read error");
  return text.str();
}

// Each line without its comment ('#' onwards), with its number; blank lines skipped.
template <class Visit>
Status for_each_line(const std::string& text, Visit visit) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
    VISVOL_RETURN_IF_ERROR(visit(line, line_no));
  }
  return Status::ok_status();
}

Status check_count(const PathFile& out, const std::string& path) {
  if (out.points.size() < 2) return invalid_argument(path + ": fewer than 2 points");
  return Status::ok_status();
}

// "x y" or "x y z" per line.
Result<PathFile> parse_text_points(const std::string& text, const std::string& path) {
  PathFile out;
  int columns = 0;
  std::vector<double> v;
  const Status s = for_each_line(text, [&](const std::string& line, int line_no) {
    const std::string where = path + ": line " + std::to_string(line_no) + ": ";
    if (!parse_numbers(line, v)) {
      if (columns == 0 && line_no == 1) return Status::ok_status();  // a header
      return invalid_argument(where + "'" + quoted(line) + "' is not numbers x y [z]");
    }
    if (v.size() != 2 && v.size() != 3) {
      return invalid_argument(where + std::to_string(v.size()) + " numbers; expected x y or x y z");
    }
    if (columns == 0) columns = static_cast<int>(v.size());
    if (static_cast<int>(v.size()) != columns) {
      return invalid_argument(where + std::to_string(v.size()) + " numbers, earlier lines " + std::to_string(columns));
    }
    for (double d : v) {
      if (!std::isfinite(d)) return invalid_argument(where + "not finite");
    }
    out.points.push_back({v[0], v[1], v.size() == 3 ? v[2] : 0.0});
    return Status::ok_status();
  });
  VISVOL_RETURN_IF_ERROR(s);
  VISVOL_RETURN_IF_ERROR(check_count(out, path));
  out.has_heights = columns == 3;
  return out;
}

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    const std::size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
    out.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
  }
  return out;
}

bool finite_number(const std::string& s, double& v) {
  char* end = nullptr;
  errno = 0;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && errno != ERANGE && std::isfinite(v);
}

// The first line that is not blank or a comment names x_m: a plan CSV.
bool is_plan_csv(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
    const std::vector<std::string> cells = split_commas(line);
    return std::find(cells.begin(), cells.end(), "x_m") != cells.end();
  }
  return false;
}

// The CSV `visvol plan` writes: columns found by the header's names.
Result<PathFile> parse_plan_csv(const std::string& text, const std::string& path) {
  PathFile out;
  out.format = PathFormat::plan_csv;
  out.has_heights = true;
  int col_x = -1, col_y = -1, col_z = -1, col_fp = -1;
  std::size_t columns = 0;
  const Status s = for_each_line(text, [&](const std::string& line, int line_no) {
    const std::string where = path + ": line " + std::to_string(line_no) + ": ";
    const std::vector<std::string> cells = split_commas(line);
    if (columns == 0) {
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const int ci = static_cast<int>(c);
        if (cells[c] == "x_m") col_x = ci;
        if (cells[c] == "y_m") col_y = ci;
        if (cells[c] == "z_m") col_z = ci;
        if (cells[c] == "fp") col_fp = ci;
      }
      if (col_y < 0 || col_z < 0) {
        return invalid_argument(where + "the header names x_m but not " + (col_y < 0 ? "y_m" : "z_m"));
      }
      columns = cells.size();
      return Status::ok_status();
    }
    if (cells.size() != columns) {
      return invalid_argument(where + std::to_string(cells.size()) + " columns, the header has " +
                              std::to_string(columns));
    }
    double v[4] = {0, 0, 0, 0};
    const int wanted[4] = {col_x, col_y, col_z, col_fp};
    for (int k = 0; k < 4; ++k) {
      if (wanted[k] < 0) continue;
      const std::string& cell = cells[static_cast<std::size_t>(wanted[k])];
      if (!finite_number(cell, v[k])) return invalid_argument(where + "'" + quoted(cell) + "' is not a finite number");
    }
    if (col_fp >= 0 && !(v[3] >= 0 && v[3] <= 1)) {
      return invalid_argument(where + "fp " + cells[static_cast<std::size_t>(col_fp)] + " is outside [0, 1]");
    }
    out.points.push_back({v[0], v[1], v[2]});
    if (col_fp >= 0) out.fp.push_back(v[3]);
    return Status::ok_status();
  });
  VISVOL_RETURN_IF_ERROR(s);
  VISVOL_RETURN_IF_ERROR(check_count(out, path));
  return out;
}

using LineStrings = std::vector<std::pair<const nlohmann::json*, const nlohmann::json*>>;

const std::string* type_of(const nlohmann::json& j) {
  if (!j.is_object() || !j.contains("type") || !j["type"].is_string()) return nullptr;
  return j["type"].get_ptr<const std::string*>();
}

// The LineStrings of a GeoJSON geometry, Feature or FeatureCollection, each
// with its Feature's properties (`none` for a bare geometry); the other
// geometry types met go to `others`. RFC 7946 nests no deeper than that.
void collect_line_strings(const nlohmann::json& root, const nlohmann::json& none, LineStrings& out,
                          std::vector<std::string>& others) {
  const auto geometry = [&](const nlohmann::json& g, const nlohmann::json& properties) {
    const std::string* type = type_of(g);
    if (type != nullptr && *type == "LineString") {
      out.emplace_back(&g, &properties);
    } else {
      others.push_back(type != nullptr ? *type : std::string("a geometry with no type"));
    }
  };
  const auto feature = [&](const nlohmann::json& f) {
    const std::string* type = type_of(f);
    if (type == nullptr || *type != "Feature" || !f.contains("geometry")) return;
    geometry(f["geometry"], f.contains("properties") ? f["properties"] : none);
  };
  const std::string* type = type_of(root);
  if (type == nullptr) return;
  if (*type == "FeatureCollection") {
    if (!root.contains("features") || !root["features"].is_array()) return;
    for (const nlohmann::json& f : root["features"]) feature(f);
  } else if (*type == "Feature") {
    feature(root);
  } else {
    geometry(root, none);
  }
}

// properties.vertex_fp of a plan's GeoJSON: one F_p in [0, 1] per vertex.
Status read_vertex_fp(const nlohmann::json& properties, std::size_t vertices, const std::string& path,
                      std::vector<double>& fp) {
  if (!properties.is_object() || !properties.contains("vertex_fp")) return Status::ok_status();
  const nlohmann::json& v = properties["vertex_fp"];
  if (!v.is_array() || v.size() != vertices) {
    return invalid_argument(path + ": properties.vertex_fp is not an array of " + std::to_string(vertices) +
                            " numbers (one per vertex)");
  }
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number() || !(v[i].get<double>() >= 0 && v[i].get<double>() <= 1)) {
      return invalid_argument(path + ": properties.vertex_fp[" + std::to_string(i) + "] is not a number in [0, 1]");
    }
    fp.push_back(v[i].get<double>());
  }
  return Status::ok_status();
}

// Positions [longitude, latitude(, height)] in degrees and metres.
Status read_positions(const nlohmann::json& coordinates, const std::string& path, PathFile& out) {
  if (!coordinates.is_array()) return invalid_argument(path + ": the LineString has no coordinates array");
  std::size_t dims = 0;
  for (std::size_t i = 0; i < coordinates.size(); ++i) {
    const nlohmann::json& c = coordinates[i];
    const std::string where = path + ": coordinates[" + std::to_string(i) + "]: ";
    if (!c.is_array() || c.size() < 2) return invalid_argument(where + "not a position [longitude, latitude, height]");
    const std::size_t n = std::min<std::size_t>(c.size(), 3);  // RFC 7946: further elements are not positions
    if (dims == 0) dims = n;
    if (n != dims) {
      return invalid_argument(where + std::to_string(n) + " numbers, earlier positions " + std::to_string(dims));
    }
    double v[3] = {0, 0, 0};
    for (std::size_t k = 0; k < n; ++k) {
      if (!c[k].is_number() || !std::isfinite(c[k].get<double>())) {
        return invalid_argument(where + "not finite numbers");
      }
      v[k] = c[k].get<double>();
    }
    if (std::fabs(v[0]) > 180 || std::fabs(v[1]) > 90) {
      return invalid_argument(where + "(" + fixed(v[0], 6) + ", " + fixed(v[1], 6) +
                              ") is not a WGS84 longitude and latitude in degrees");
    }
    out.points.push_back({v[0], v[1], v[2]});
  }
  out.has_heights = dims == 3;
  return Status::ok_status();
}

// The GeoJSON `visvol plan` writes (or any with one LineString), to the pack's CRS.
Result<PathFile> parse_geojson(const std::string& text, const std::string& path, const std::string& crs_wkt) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return invalid_argument(path + ": not valid JSON: " + e.what());
  }
  const nlohmann::json no_properties;
  LineStrings lines;
  std::vector<std::string> others;
  collect_line_strings(j, no_properties, lines, others);
  if (lines.size() != 1) {
    return invalid_argument(path + ": " + std::to_string(lines.size()) + " LineStrings; a path file has exactly one" +
                            (others.empty() ? "" : " (found " + others.front() + ")"));
  }
  PathFile out;
  out.format = PathFormat::geojson;
  const nlohmann::json& line = *lines.front().first;
  if (!line.contains("coordinates")) return invalid_argument(path + ": the LineString has no coordinates");
  VISVOL_RETURN_IF_ERROR(read_positions(line["coordinates"], path, out));
  VISVOL_RETURN_IF_ERROR(check_count(out, path));
  VISVOL_RETURN_IF_ERROR(read_vertex_fp(*lines.front().second, out.points.size(), path, out.fp));
  if (crs_wkt.empty()) {
    return invalid_argument(path + ": a GeoJSON path is in WGS84 longitude and latitude, and there is no pack CRS "
                                   "to convert it to (use the CSV or x y z text in the pack's CRS)");
  }
  Result<std::vector<Vec3>> projected = from_wgs84(out.points, crs_wkt);
  if (!projected.ok()) return projected.status().with_context(path);
  out.points = std::move(*projected);
  return out;
}

}  // namespace

Result<PathFile> read_path_file(const std::string& path, const std::string& crs_wkt) {
  Result<std::string> text = read_whole_file(path);
  if (!text.ok()) return text.status();
  const std::size_t first = text->find_first_not_of(" \t\r\n");
  if (first != std::string::npos && (*text)[first] == '{') return parse_geojson(*text, path, crs_wkt);
  if (is_plan_csv(*text)) return parse_plan_csv(*text, path);
  return parse_text_points(*text, path);
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

namespace {

// OGR's transformation between the pack's CRS and WGS84, x east and y north
// (longitude first) on both sides.
Result<std::unique_ptr<OGRCoordinateTransformation>> wgs84_transform(const std::string& crs_wkt, bool to_wgs84) {
  if (crs_wkt.empty()) return Status(Errc::unsupported, "the pack has no CRS, so there is no WGS84 position");
  OGRSpatialReference pack, wgs84;
  if (pack.importFromWkt(crs_wkt.c_str()) != OGRERR_NONE) return corrupt("the pack's CRS WKT does not parse");
  wgs84.SetWellKnownGeogCS("WGS84");
  pack.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(
      to_wgs84 ? OGRCreateCoordinateTransformation(&pack, &wgs84) : OGRCreateCoordinateTransformation(&wgs84, &pack));
  if (!ct) return Status(Errc::unsupported, "no transformation between the pack's CRS and WGS84");
  return ct;
}

// Heights stay the DEM's (mean sea level) both ways.
Result<std::vector<Vec3>> transform_xy(const std::vector<Vec3>& points, const std::string& crs_wkt, bool to_wgs84) {
  Result<std::unique_ptr<OGRCoordinateTransformation>> ct = wgs84_transform(crs_wkt, to_wgs84);
  if (!ct.ok()) return ct.status();
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    double x = points[i].x(), y = points[i].y();
    if (!(*ct)->Transform(1, &x, &y) || !std::isfinite(x) || !std::isfinite(y)) {
      return invalid_argument("path vertex " + std::to_string(i) + " cannot be converted " +
                              (to_wgs84 ? "to WGS84" : "from WGS84 to the pack's CRS"));
    }
    out.push_back({x, y, points[i].z()});
  }
  return out;
}

}  // namespace

Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt) {
  return transform_xy(vertices, crs_wkt, true);
}

Result<std::vector<Vec3>> from_wgs84(const std::vector<Vec3>& lon_lat_h, const std::string& crs_wkt) {
  return transform_xy(lon_lat_h, crs_wkt, false);
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
