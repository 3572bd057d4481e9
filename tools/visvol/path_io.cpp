// Reading path files (path_io.hpp: read_path_file, but a .plan: plan_file_read.cpp)
// and lifting a 2D path over the terrain.
#include "path_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "base/decimal_text.hpp"
#include "base/tolerances.hpp"
#include "io/input_file.hpp"
#include "io/json_input.hpp"
#include "io/json_text.hpp"
#include "path_io_detail.hpp"

namespace visvol::cli {

namespace detail {

// Characters of a bad line quoted in a message.
constexpr std::size_t kQuotedChars = 40;

std::string fixed(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

// A number for a message: fixed decimals, or 6 significant digits where that
// would print hundreds of digits (a mistyped 1e308).
std::string shown(double v, int decimals) {
  if (!(std::fabs(v) < 1e9)) {
    std::ostringstream s;
    s << v;
    return s.str();
  }
  return fixed(v, decimals);
}

// A line for a message: at most kQuotedChars, unprintable bytes as '?', so a
// binary file does not spill onto the terminal.
std::string quoted(const std::string& line) {
  std::string out;
  for (char c : line.substr(0, kQuotedChars)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  if (line.size() > kQuotedChars) out += "...";
  return out;
}

// A JSON value for a message, shortened.
std::string json_brief(const nlohmann::json& j) { return quoted(json_text(j)); }

}  // namespace detail

using detail::fixed;
using detail::json_brief;
using detail::quoted;
using detail::shown;

namespace {

// Path files are small (a 100000-segment plan's GeoJSON is under 20 MiB):
// anything larger is not a path.
constexpr std::uintmax_t kMaxPathFileBytes = 64u << 20;

// A decimal number that fits a double (1e400 does not).
bool decimal_number(const std::string& s, double& v) {
  if (!is_decimal_number(s)) return false;
  errno = 0;
  v = std::strtod(s.c_str(), nullptr);
  return errno != ERANGE || std::fabs(v) < 1;  // underflow to (near) zero is fine
}

// Numbers of a line: separators are spaces, tabs and commas.
bool parse_numbers(std::string line, std::vector<double>& out) {
  for (char& c : line) {
    if (c == ',' || c == '\t' || c == ';') c = ' ';
  }
  std::istringstream in(line);
  out.clear();
  std::string word;
  while (in >> word) {
    double v = 0;
    if (!decimal_number(word, v)) return false;
    out.push_back(v);
  }
  return true;
}

Result<std::string> read_whole_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return io_error(path + ": is a folder, not a path file");
  Result<InputFile> in = InputFile::open(path);
  if (!in.ok()) return in.status();
  if (in->size_bytes() > kMaxPathFileBytes) {
    return invalid_argument(path + ": " + std::to_string(in->size_bytes() >> 20) +
                            " MiB is too large for a path file (at most " + std::to_string(kMaxPathFileBytes >> 20) +
                            " MiB)");
  }
  return in->read_all(static_cast<std::size_t>(kMaxPathFileBytes));
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
      // a header ("x y z"); a first line with a number in it is a mistyped
      // point, not a header, and is never dropped
      if (columns == 0 && line_no == 1 && line.find_first_of("0123456789") == std::string::npos) {
        return Status::ok_status();
      }
      // one that begins with a letter may be a header with digits
      const std::size_t start = line.find_first_not_of(" \t,;");
      const bool header_like = columns == 0 && line_no == 1 && start != std::string::npos &&
                               std::isalpha(static_cast<unsigned char>(line[start])) != 0;
      return invalid_argument(where + "'" + quoted(line) + "' is not numbers x y [z]" +
                              (header_like ? " (if it is a header, start it with '#')" : ""));
    }
    if (v.size() != 2 && v.size() != 3) {
      return invalid_argument(where + std::to_string(v.size()) + " numbers; expected x y or x y z");
    }
    if (columns == 0) columns = static_cast<int>(v.size());
    if (static_cast<int>(v.size()) != columns) {
      return invalid_argument(where + std::to_string(v.size()) + " numbers, earlier lines " + std::to_string(columns));
    }
    out.points.push_back({v[0], v[1], v.size() == 3 ? v[2] : 0.0});  // finite: decimal_number()
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

bool finite_number(const std::string& s, double& v) { return decimal_number(s, v) && std::isfinite(v); }

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
        for (auto [name, col] :
             {std::pair{"x_m", &col_x}, std::pair{"y_m", &col_y}, std::pair{"z_m", &col_z}, std::pair{"fp", &col_fp}}) {
          if (cells[c] != name) continue;
          // two columns of one name: which is the path is not for the reader to guess
          if (*col >= 0) {
            return invalid_argument(where + "the header names " + name + " twice (columns " + std::to_string(*col + 1) +
                                    " and " + std::to_string(ci + 1) + ")");
          }
          *col = ci;
        }
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
// geometry types met go to `others`, and a FeatureCollection's members that
// are not Features (or have no geometry) to `strays`. RFC 7946 nests no
// deeper than that.
void collect_line_strings(const nlohmann::json& root, const nlohmann::json& none, LineStrings& out,
                          std::vector<std::string>& others, std::vector<std::string>& strays) {
  const auto geometry = [&](const nlohmann::json& g, const nlohmann::json& properties) {
    const std::string* type = type_of(g);
    if (type != nullptr && *type == "LineString") {
      out.emplace_back(&g, &properties);
    } else {
      others.push_back(type != nullptr ? *type : std::string("a geometry with no type"));
    }
  };
  const auto feature = [&](const nlohmann::json& f, const std::string& where) {
    const std::string* type = type_of(f);
    if (type == nullptr || *type != "Feature" || !f.contains("geometry")) {
      strays.push_back(where +
                       (f.is_object() && f.contains("type") ? " (type " + json_brief(f["type"]) + ")" : " (no type)"));
      return;
    }
    if (f["geometry"].is_null()) return;  // RFC 7946: a Feature without a location
    geometry(f["geometry"], f.contains("properties") ? f["properties"] : none);
  };
  const std::string* type = type_of(root);
  if (type == nullptr) return;
  if (*type == "FeatureCollection") {
    if (!root.contains("features") || !root["features"].is_array()) return;
    for (std::size_t i = 0; i < root["features"].size(); ++i)
      feature(root["features"][i], "features[" + std::to_string(i) + "]");
  } else if (*type == "Feature") {
    feature(root, "the Feature");
  } else {
    geometry(root, none);
  }
}

// RFC 7946 dropped the "crs" member: positions are WGS84 longitude and
// latitude. An older file's "crs" naming another CRS (NAD27, a UTM zone) is
// refused: read as WGS84 its positions would be tens of metres off or more.
Status check_legacy_crs(const nlohmann::json& object, const std::string& path) {
  if (!object.is_object() || !object.contains("crs")) return Status::ok_status();
  const nlohmann::json& crs = object["crs"];
  std::string name;
  if (crs.is_object() && crs.contains("properties") && crs["properties"].is_object() &&
      crs["properties"].contains("name") && crs["properties"]["name"].is_string()) {
    name = crs["properties"]["name"].get<std::string>();
  }
  for (const char* wgs84 : {"urn:ogc:def:crs:OGC:1.3:CRS84", "urn:ogc:def:crs:OGC::CRS84", "urn:ogc:def:crs:EPSG::4326",
                            "EPSG:4326", "CRS84"}) {
    if (name == wgs84) return Status::ok_status();
  }
  return invalid_argument(path + ": \"crs\" " + json_brief(crs) +
                          " is not WGS84 longitude and latitude (CRS84), the only CRS a GeoJSON path is read in "
                          "(RFC 7946)");
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
      return invalid_argument(where + "(" + shown(v[0], 6) + ", " + shown(v[1], 6) +
                              ") is not a WGS84 longitude and latitude in degrees");
    }
    out.points.push_back({v[0], v[1], v[2]});
  }
  out.has_heights = dims == 3;
  return Status::ok_status();
}

// What a visvol GeoJSON written before its heights were ellipsoidal said of
// them: such a file's heights are the DEM's, read as they are.
constexpr const char* kOrthometricGeoJsonReference = "the DEM's vertical datum (mean sea level)";

// Whether a GeoJSON's heights are above mean sea level rather than the WGS84
// ellipsoid (RFC 7946's, the default): a `vertical_datum` naming EGM96 or
// mean sea level says so, as does a visvol GeoJSON from before its heights
// were ellipsoidal. A datum named otherwise is refused: read as ellipsoidal,
// heights above another datum would be tens of metres off.
Result<bool> heights_are_orthometric(const nlohmann::json& properties, const std::string& path) {
  if (!properties.is_object()) return false;
  const auto datum = properties.find("vertical_datum");
  if (datum != properties.end()) {
    std::string name = datum->is_string() ? datum->get<std::string>() : std::string();
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (name.find("ellipsoid") != std::string::npos) return false;
    if (name.find("egm96") != std::string::npos || name.find("mean sea level") != std::string::npos) return true;
    return invalid_argument(path + ": vertical_datum " + json_brief(*datum) +
                            " is not one visvol converts: it reads heights above the WGS 84 ellipsoid (RFC 7946) or "
                            "above mean sea level (EGM96)");
  }
  const auto it = properties.find("height_reference");
  return it != properties.end() && it->is_string() && it->get<std::string>() == kOrthometricGeoJsonReference;
}

// The GeoJSON `visvol plan` writes (or any with one LineString), to the pack's
// CRS and the DEM's (orthometric) heights.
Result<PathFile> parse_geojson(const nlohmann::json& j, const std::string& path, const std::string& crs_wkt) {
  const nlohmann::json no_properties;
  LineStrings lines;
  std::vector<std::string> others, strays;
  collect_line_strings(j, no_properties, lines, others, strays);
  if (lines.size() != 1) {
    return invalid_argument(path + ": " + std::to_string(lines.size()) + " LineStrings; a path file has exactly one" +
                            (others.empty() ? "" : " (found " + others.front() + ")"));
  }
  // nothing beside the path that could be another route, left out unseen
  if (!strays.empty()) {
    return invalid_argument(path + ": " + strays.front() +
                            " is not a Feature with a geometry; a path file is one LineString (and may hold points)");
  }
  for (const std::string& other : others) {
    if (other != "Point" && other != "MultiPoint") {
      return invalid_argument(path + ": a " + other +
                              " beside the path's LineString; a path file is one LineString (and may hold points)");
    }
  }
  // the root, and (GeoJSON 2008 allowed it there too) each Feature and geometry
  VISVOL_RETURN_IF_ERROR(check_legacy_crs(j, path));
  const auto check_feature = [&](const nlohmann::json& f) {
    VISVOL_RETURN_IF_ERROR(check_legacy_crs(f, path));
    return f.is_object() && f.contains("geometry") ? check_legacy_crs(f["geometry"], path) : Status::ok_status();
  };
  if (j.is_object() && j.contains("features") && j["features"].is_array()) {
    for (const nlohmann::json& f : j["features"]) VISVOL_RETURN_IF_ERROR(check_feature(f));
  } else {
    VISVOL_RETURN_IF_ERROR(check_feature(j));
  }
  PathFile out;
  out.format = PathFormat::geojson;
  const nlohmann::json& line = *lines.front().first;
  const nlohmann::json& properties = *lines.front().second;
  if (!line.contains("coordinates")) return invalid_argument(path + ": the LineString has no coordinates");
  VISVOL_RETURN_IF_ERROR(read_positions(line["coordinates"], path, out));
  VISVOL_RETURN_IF_ERROR(check_count(out, path));
  VISVOL_RETURN_IF_ERROR(read_vertex_fp(properties, out.points.size(), path, out.fp));
  if (properties.is_object() && properties.contains("requirements_met") &&
      properties["requirements_met"].is_boolean()) {
    out.requirements_met = properties["requirements_met"].get<bool>();
  }
  if (crs_wkt.empty()) {
    return invalid_argument(path +
                            ": a GeoJSON path is in WGS84 longitude and latitude, and there is no pack CRS "
                            "to convert it to (use the CSV or x y z text in the pack's CRS)");
  }
  // RFC 7946: heights above the WGS84 ellipsoid; the pack's are the DEM's
  Result<bool> orthometric_heights = heights_are_orthometric(properties, path);
  if (!orthometric_heights.ok()) return orthometric_heights.status();
  if (out.has_heights && !*orthometric_heights) {
    Result<std::vector<Vec3>> orthometric = ellipsoidal_to_orthometric(out.points);
    if (!orthometric.ok()) return orthometric.status().with_context(path + ": heights");
    out.points = std::move(*orthometric);
  }
  Wgs84Conversion conversion;
  Result<std::vector<Vec3>> projected = from_wgs84(out.points, crs_wkt, &conversion);
  if (!projected.ok()) return projected.status().with_context(path);
  out.points = std::move(*projected);
  if (std::string note = wgs84_accuracy_note(conversion); !note.empty()) out.notes.push_back(std::move(note));
  return out;
}

// A JSON document: a QGroundControl plan (it has a fileType) or GeoJSON.
Result<PathFile> parse_json_path(const std::string& text, const std::string& path, const std::string& crs_wkt) {
  Result<nlohmann::json> parsed = parse_json_input(text, path);
  if (!parsed.ok()) return parsed.status();
  const nlohmann::json& j = *parsed;
  if (j.is_object() && j.contains("fileType")) return detail::parse_qgc_plan(j, path, crs_wkt);
  return parse_geojson(j, path, crs_wkt);
}

}  // namespace

namespace {

Result<PathFile> parse_path_text(std::string& text, const std::string& path, const std::string& crs_wkt) {
  // a UTF-8 byte order mark, as editors on some systems save text
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '{') return parse_json_path(text, path, crs_wkt);
  if (is_plan_csv(text)) {
    Result<PathFile> csv = parse_plan_csv(text, path);
    // the verdict visvol plan wrote in its '#' lines
    if (csv.ok() && text.find("\n# requirements: NOT MET") != std::string::npos) csv->requirements_met = false;
    if (csv.ok() && text.find("\n# requirements: all met") != std::string::npos) csv->requirements_met = true;
    return csv;
  }
  return parse_text_points(text, path);
}

}  // namespace

Result<PathFile> read_path_file(const std::string& path, const std::string& crs_wkt) {
  Result<std::string> text = read_whole_file(path);
  if (!text.ok()) return text.status();
  Result<PathFile> read = parse_path_text(*text, path, crs_wkt);
  if (!read.ok()) return read;
  // a path that goes nowhere would pass every check it is given
  const std::vector<Vec3>& p = read->points;
  const bool moves = std::any_of(p.begin(), p.end(), [&](const Vec3& q) { return (q - p.front()).norm() >= 0.01; });
  if (!moves) {
    return invalid_argument(path + ": all " + std::to_string(p.size()) +
                            " points are the same position (within 1 cm): a path needs two different points");
  }
  return read;
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

}  // namespace visvol::cli
