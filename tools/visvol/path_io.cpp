#include "path_io.hpp"

#include <ogr_spatialref.h>
#include <proj.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
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

#include "base/decimal_text.hpp"
#include "base/tolerances.hpp"
#include "io/atomic_file.hpp"
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

namespace {

struct ProjContextFree {
  void operator()(PJ_CONTEXT* c) const { proj_context_destroy(c); }
};
struct ProjFree {
  void operator()(PJ* p) const { proj_destroy(p); }
};
using ProjContext = std::unique_ptr<PJ_CONTEXT, ProjContextFree>;
using ProjObject = std::unique_ptr<PJ, ProjFree>;

// A pack's CRS must be projected, in metres, as its grid is.
Status check_pack_crs(const std::string& crs_wkt) {
  if (crs_wkt.empty()) return Status(Errc::unsupported, "the pack has no CRS, so there is no WGS84 position");
  OGRSpatialReference pack;
  if (pack.importFromWkt(crs_wkt.c_str()) != OGRERR_NONE) return corrupt("the pack's CRS WKT does not parse");
  // a CRS in degrees (or feet) would place the grid wrong
  if (!pack.IsProjected() || std::fabs(pack.GetLinearUnits() - 1.0) > 1e-9) {
    return corrupt("the pack's CRS (" + std::string(pack.GetName() ? pack.GetName() : "unnamed") +
                   ") is not a projected CRS in metres, as its grid is");
  }
  return Status::ok_status();
}

// PROJ's transformation between the pack's CRS and WGS84, x east and y north
// (longitude first) on both sides: at each point the most accurate one whose
// area holds it and whose grids are installed (no network). It keeps the
// coarsest operation it used, to say how far WGS84 positions can be trusted
// (NAD27 without NOAA's grid: a datum shift good to 7 m).
class Wgs84Transform {
 public:
  static Result<Wgs84Transform> create(const std::string& crs_wkt) {
    VISVOL_RETURN_IF_ERROR(check_pack_crs(crs_wkt));
    Wgs84Transform t;
    t.ctx_.reset(proj_context_create());
    if (!t.ctx_) return resource_error("PROJ: no context");
    proj_log_level(t.ctx_.get(), PJ_LOG_NONE);  // failures are reported in words
    proj_context_set_enable_network(t.ctx_.get(), 0);
    const ProjObject pack(proj_create(t.ctx_.get(), crs_wkt.c_str())), wgs84(proj_create(t.ctx_.get(), "EPSG:4326"));
    if (!pack || !wgs84) return Status(Errc::unsupported, "PROJ does not read the pack's CRS or know EPSG:4326");
    const ProjObject any_order(proj_create_crs_to_crs_from_pj(t.ctx_.get(), pack.get(), wgs84.get(), nullptr, nullptr));
    if (any_order) t.pj_.reset(proj_normalize_for_visualization(t.ctx_.get(), any_order.get()));
    if (!t.pj_) return Status(Errc::unsupported, "no transformation between the pack's CRS and WGS84");
    return t;
  }

  // False when the point does not convert.
  bool convert(double& x, double& y, bool to_wgs84) {
    // no time (HUGE_VAL): a time-dependent transformation would take year 0
    const PJ_COORD in = proj_coord(x, y, 0, HUGE_VAL);
    const PJ_DIRECTION direction = to_wgs84 ? PJ_FWD : PJ_INV;
    const PJ_COORD r = proj_trans(pj_.get(), direction, in);
    if (!std::isfinite(r.xy.x) || !std::isfinite(r.xy.y) || r.xy.x == HUGE_VAL) return false;
    x = r.xy.x;
    y = r.xy.y;
    // which operation PROJ took costs 45 us a point to ask (a copy of it):
    // asked again only where the last one's answer differs from this one's
    if (last_op_) {
      const PJ_COORD same = proj_trans(last_op_.get(), direction, in);
      if (same.xy.x == r.xy.x && same.xy.y == r.xy.y) return true;
    }
    note_operation();
    return true;
  }

  const Wgs84Conversion& coarsest() const { return coarsest_; }

 private:
  void note_operation() {
    last_op_.reset(proj_trans_get_last_used_operation(pj_.get()));
    const PJ* op = last_op_.get();
    if (op == nullptr) {
      if (coarsest_.operation.empty()) coarsest_ = {"a transformation PROJ does not name", -1};
      return;
    }
    const char* name = proj_get_name(op);
    if (name != nullptr && name == last_name_) return;
    last_name_ = name != nullptr ? name : "";
    // the longitude-first order is ours, not the transformation's
    const std::string order = " + axis order change (2D)";
    std::string shown_name = last_name_;
    if (shown_name.size() > order.size() &&
        shown_name.compare(shown_name.size() - order.size(), order.size(), order) == 0)
      shown_name.resize(shown_name.size() - order.size());
    const double accuracy = proj_coordoperation_get_accuracy(ctx_.get(), op);
    // a pure change of projection is exact; PROJ says -1 (unknown) for some
    const bool exact =
        proj_get_type(op) == PJ_TYPE_CONVERSION || (accuracy < 0 && last_name_.find(" to ") == std::string::npos);
    const double a = exact ? 0.0 : accuracy;
    const bool coarser = coarsest_.operation.empty() || (a < 0 && coarsest_.accuracy_m >= 0) ||
                         (coarsest_.accuracy_m >= 0 && a > coarsest_.accuracy_m);
    if (coarser) coarsest_ = {shown_name, a};
  }

  ProjContext ctx_;
  ProjObject pj_;
  ProjObject last_op_;  // the operation PROJ took for the last point asked
  std::string last_name_;
  Wgs84Conversion coarsest_;
};

// Heights stay the DEM's (mean sea level) both ways.
Result<std::vector<Vec3>> transform_xy(const std::vector<Vec3>& points, const std::string& crs_wkt, bool to_wgs84,
                                       Wgs84Conversion* conversion = nullptr) {
  Result<Wgs84Transform> ct = Wgs84Transform::create(crs_wkt);
  if (!ct.ok()) return ct.status();
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    double x = points[i].x(), y = points[i].y();
    if (!std::isfinite(x) || !std::isfinite(y) || !ct->convert(x, y, to_wgs84)) {
      return invalid_argument("path vertex " + std::to_string(i) + " cannot be converted " +
                              (to_wgs84 ? "to WGS84" : "from WGS84 to the pack's CRS"));
    }
    if (to_wgs84 && !(std::fabs(x) <= 180 && std::fabs(y) <= 90)) {
      return invalid_argument("path vertex " + std::to_string(i) + " converts to longitude " + shown(x, 6) +
                              ", latitude " + shown(y, 6) + ": not a WGS84 position");
    }
    out.push_back({x, y, points[i].z()});
  }
  if (conversion != nullptr) *conversion = ct->coarsest();
  return out;
}

}  // namespace

Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt,
                                   Wgs84Conversion* conversion) {
  return transform_xy(vertices, crs_wkt, true, conversion);
}

Result<std::vector<Vec3>> from_wgs84(const std::vector<Vec3>& lon_lat_h, const std::string& crs_wkt,
                                     Wgs84Conversion* conversion) {
  return transform_xy(lon_lat_h, crs_wkt, false, conversion);
}

std::string Wgs84Conversion::describe() const {
  if (accuracy_m == 0) return operation + " (exact)";
  if (accuracy_m < 0) return operation + " (accuracy not known)";
  char text[32];
  std::snprintf(text, sizeof text, "%g", accuracy_m);
  return operation + " (accurate to " + text + " m by EPSG)";
}

std::string wgs84_accuracy_note(const Wgs84Conversion& c) {
  if (c.operation.empty() || (c.accuracy_m >= 0 && c.accuracy_m <= kTrustedWgs84AccuracyM)) return {};
  return "WGS84 positions by " + c.describe() +
         ", the finest transformation PROJ has here: the path in WGS84 and the path on the pack's terrain may "
         "lie that far apart";
}

// ---- Heights: EGM96 orthometric <-> WGS84 ellipsoidal ----

namespace {

constexpr const char* kOrthometricCrs = "EPSG:4326+5773";  // WGS 84 + EGM96 height
constexpr const char* kEllipsoidalCrs = "EPSG:4979";       // WGS 84 (3D): height above the ellipsoid
// The grid PROJ's EPSG transformation uses, and its name before PROJ 7.
constexpr const char* kGeoidGridNames = "us_nga_egm96_15.tif (egm96_15.gtx before PROJ 7)";

struct ProjListFree {
  void operator()(PJ_OBJ_LIST* l) const { proj_list_destroy(l); }
};
struct ProjFactoryFree {
  void operator()(PJ_OPERATION_FACTORY_CONTEXT* f) const { proj_operation_factory_context_destroy(f); }
};
struct GeoidShift {
  std::vector<Vec3> points;
  std::string grid;  // the grid PROJ used
};

Status geoid_missing(const std::string& grids) {
  return Status(Errc::unsupported,
                "the EGM96 geoid grid " + grids +
                    " is not installed in PROJ's data folder (Debian: proj-data, /usr/share/proj; or PROJ_DATA): "
                    "heights above the WGS84 ellipsoid (GeoJSON, RFC 7946) need it");
}

// Orthometric (EGM96) to ellipsoidal heights (WGS84) or back at WGS84
// (longitude, latitude, height) points: the EPSG transformation through the
// EGM96 grid, never PROJ's "ballpark" one that leaves heights unchanged, and
// no grid fetched from the network. A context of its own per call (GDAL keeps
// its own), so this is thread-compatible.
Result<GeoidShift> shift_heights(const std::vector<Vec3>& lon_lat_h, bool to_ellipsoidal) {
  const ProjContext ctx(proj_context_create());
  if (!ctx) return resource_error("PROJ: no context");
  proj_log_level(ctx.get(), PJ_LOG_NONE);  // failures are reported below, in words
  proj_context_set_enable_network(ctx.get(), 0);
  const ProjObject source(proj_create(ctx.get(), kOrthometricCrs)), target(proj_create(ctx.get(), kEllipsoidalCrs));
  if (!source || !target) {
    return Status(Errc::unsupported, std::string("PROJ does not know ") + kOrthometricCrs + " or " + kEllipsoidalCrs +
                                         " (is its database proj.db installed?)");
  }
  const std::unique_ptr<PJ_OPERATION_FACTORY_CONTEXT, ProjFactoryFree> factory(
      proj_create_operation_factory_context(ctx.get(), nullptr));
  if (!factory) return resource_error("PROJ: no operation factory");
  proj_operation_factory_context_set_allow_ballpark_transformations(ctx.get(), factory.get(), 0);
  // list the transformations whether their grids are here or not, to name a missing one
  proj_operation_factory_context_set_grid_availability_use(ctx.get(), factory.get(), PROJ_GRID_AVAILABILITY_IGNORED);
  proj_operation_factory_context_set_spatial_criterion(ctx.get(), factory.get(),
                                                       PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  const std::unique_ptr<PJ_OBJ_LIST, ProjListFree> operations(
      proj_create_operations(ctx.get(), source.get(), target.get(), factory.get()));
  const int count = operations ? proj_list_get_count(operations.get()) : 0;
  ProjObject chosen;
  std::string grid, missing;
  for (int i = 0; i < count && !chosen; ++i) {
    ProjObject op(proj_list_get(ctx.get(), operations.get(), i));
    if (!op) continue;
    const int grids = proj_coordoperation_get_grid_used_count(ctx.get(), op.get());
    bool available = grids > 0;  // a transformation without a grid does not apply the geoid
    std::string names;
    for (int g = 0; g < grids; ++g) {
      const char *short_name = nullptr, *full_name = nullptr, *package = nullptr, *url = nullptr;
      int direct_download = 0, open_license = 0, here = 0;
      if (!proj_coordoperation_get_grid_used(ctx.get(), op.get(), g, &short_name, &full_name, &package, &url,
                                             &direct_download, &open_license, &here)) {
        available = false;
        continue;
      }
      names += (names.empty() ? "" : ", ") + std::string(short_name != nullptr ? short_name : "?");
      if (here == 0) available = false;
    }
    if (available) {
      chosen.reset(proj_normalize_for_visualization(ctx.get(), op.get()));  // longitude, latitude order
      grid = names;
    } else if (missing.empty() && !names.empty()) {
      missing = names;
    }
  }
  if (!chosen) return geoid_missing(missing.empty() ? kGeoidGridNames : missing);

  GeoidShift out;
  out.grid = grid;
  out.points.reserve(lon_lat_h.size());
  for (std::size_t i = 0; i < lon_lat_h.size(); ++i) {
    const Vec3& p = lon_lat_h[i];
    const PJ_COORD shifted =
        proj_trans(chosen.get(), to_ellipsoidal ? PJ_FWD : PJ_INV, proj_coord(p.x(), p.y(), p.z(), 0));
    if (!std::isfinite(shifted.xyz.z) || shifted.xyz.z == HUGE_VAL) {
      const int err = proj_context_errno(ctx.get());
      return invalid_argument("point " + std::to_string(i) + " (longitude " + shown(p.x(), 6) + ", latitude " +
                              shown(p.y(), 6) + "): no EGM96 geoid height there" +
                              (err != 0 ? std::string(" (") + proj_context_errno_string(ctx.get(), err) + ")" : ""));
    }
    out.points.push_back({p.x(), p.y(), shifted.xyz.z});
  }
  return out;
}

}  // namespace

Result<std::vector<Vec3>> orthometric_to_ellipsoidal(const std::vector<Vec3>& lon_lat_h) {
  Result<GeoidShift> s = shift_heights(lon_lat_h, true);
  if (!s.ok()) return s.status();
  return std::move(s->points);
}

Result<std::vector<Vec3>> ellipsoidal_to_orthometric(const std::vector<Vec3>& lon_lat_h) {
  Result<GeoidShift> s = shift_heights(lon_lat_h, false);
  if (!s.ok()) return s.status();
  return std::move(s->points);
}

// ---- Outputs ----

namespace {

// The pack's CRS for a CSV comment: its name and EPSG code, no commas (a
// spreadsheet would split the line) and no '#'.
std::string crs_description(const std::string& crs_wkt) {
  if (crs_wkt.empty()) return "the pack's CRS (the pack names none)";
  OGRSpatialReference srs;
  if (srs.importFromWkt(crs_wkt.c_str()) != OGRERR_NONE) return "the pack's CRS (its WKT does not parse)";
  std::string name = srs.GetName() != nullptr ? srs.GetName() : "unnamed CRS";
  const char* authority = srs.GetAuthorityName(nullptr);
  if (authority == nullptr && srs.AutoIdentifyEPSG() == OGRERR_NONE) authority = srs.GetAuthorityName(nullptr);
  const char* code = srs.GetAuthorityCode(nullptr);
  std::string text = "the pack's CRS \"" + name + "\" (" +
                     (authority != nullptr && code != nullptr ? std::string(authority) + ":" + code : "no EPSG code") +
                     ")";
  for (char& c : text) {
    if (c == ',' || c == '#' || c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

bool all_finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

// Everything the outputs rely on, checked before any is written.
Status validate_report(const PathReport& r) {
  if (r.vertices.size() < 2) {
    return invalid_argument("path outputs: " + std::to_string(r.vertices.size()) + " vertices; a path has at least 2");
  }
  if (r.per_vertex.size() != r.vertices.size()) {
    return invalid_argument("path outputs: " + std::to_string(r.per_vertex.size()) + " per-vertex values for " +
                            std::to_string(r.vertices.size()) + " vertices");
  }
  for (std::size_t i = 0; i < r.vertices.size(); ++i) {
    if (!all_finite(r.vertices[i]) || !std::isfinite(r.per_vertex[i].fp) ||
        !std::isfinite(r.per_vertex[i].clearance_m)) {
      return invalid_argument("path outputs: vertex " + std::to_string(i) + " is not finite");
    }
  }
  // what the .plan takes from the vehicle (rt::validate would check limits it does not use)
  const rt::VehicleEnvelope& v = r.vehicle;
  const std::string vehicle = "path outputs: vehicle " + v.name + ": ";
  if (v.type != rt::VehicleType::fixed_wing && v.type != rt::VehicleType::multirotor) {
    return invalid_argument(vehicle + "type " + std::to_string(static_cast<int>(v.type)) + " is unknown");
  }
  if (!(std::isfinite(v.speed_m_per_s) && v.speed_m_per_s > 0)) {
    return invalid_argument(vehicle + "speed " + std::to_string(v.speed_m_per_s) + " m/s is not above 0");
  }
  if (!(v.max_climb_deg > 0 && v.max_climb_deg <= 90)) {
    return invalid_argument(vehicle + "max-climb " + std::to_string(v.max_climb_deg) + " deg is outside (0, 90]");
  }
  if (!(std::isfinite(v.min_turn_radius_m) && v.min_turn_radius_m >= 0)) {
    return invalid_argument(vehicle + "min-turn-radius " + std::to_string(v.min_turn_radius_m) + " m is not 0 or more");
  }
  if (!std::isfinite(r.home_ground_m)) return invalid_argument("path outputs: home_ground_m is not set");
  if (!std::isfinite(r.land_ground_m)) return invalid_argument("path outputs: land_ground_m is not set");
  return Status::ok_status();
}

// The .plan takes off from the ground below the first vertex and lands on the
// ground below the last: neither may be above its vertex.
Status check_plan_ground(const PathReport& r) {
  const auto check = [](const char* name, double ground_m, const Vec3& vertex, const char* which) {
    if (ground_m <= vertex.z()) return Status::ok_status();
    return invalid_argument(std::string(name) + " " + fixed(ground_m, 2) + " m is above the " + which + " vertex (" +
                            fixed(vertex.z(), 2) + " m): the path starts or ends below the terrain");
  };
  VISVOL_RETURN_IF_ERROR(check("home_ground_m", r.home_ground_m, r.vertices.front(), "first"));
  return check("land_ground_m", r.land_ground_m, r.vertices.back(), "last");
}

// A comment line of the CSV is one spreadsheet cell: no comma.
std::string comment_cell(std::string text) {
  std::replace(text.begin(), text.end(), ',', ';');
  return text;
}

std::string csv_text(const PathReport& r, const Result<std::vector<Vec3>>& geo, const Wgs84Conversion& conversion,
                     const Result<GeoidShift>& ellipsoidal) {
  std::ostringstream csv;
  csv << "# visvol plan path (" << r.objective << "); one row per vertex\n"
      << "# x_m y_m: " << crs_description(r.crs_wkt) << " in metres\n"
      << "# z_m: height above the DEM's vertical datum (orthometric; m; taken as EGM96 like SRTM's)\n";
  if (geo.ok()) {
    csv << "# lon_deg lat_deg: WGS84 (EPSG:4326) longitude and latitude in degrees; by "
        << comment_cell(conversion.describe()) << '\n';
  }
  if (ellipsoidal.ok()) {
    csv << "# h_ellipsoidal_m: height above the WGS84 ellipsoid (EPSG:4979) = z_m + EGM96 geoid undulation (m)\n";
  }
  csv << "# fp: F_p at the vertex in [0 1]; clearance_m: height above the terrain (m)\n";
  csv << "# requirements: " << (r.requirements_met ? "all met" : "NOT MET") << '\n';
  for (const std::string& u : r.unmet) csv << "#   unmet: " << comment_cell(u) << '\n';
  csv << "index,x_m,y_m,z_m," << (geo.ok() ? "lon_deg,lat_deg," : "") << (ellipsoidal.ok() ? "h_ellipsoidal_m," : "")
      << "fp,clearance_m\n";
  for (std::size_t i = 0; i < r.vertices.size(); ++i) {
    const Vec3& v = r.vertices[i];
    // a tenth of a millimetre: read back, a turn between vertices metres apart keeps its radius
    csv << i << ',' << fixed(v.x(), 4) << ',' << fixed(v.y(), 4) << ',' << fixed(v.z(), 4) << ',';
    if (geo.ok()) csv << fixed((*geo)[i].x(), 8) << ',' << fixed((*geo)[i].y(), 8) << ',';
    if (ellipsoidal.ok()) csv << fixed(ellipsoidal->points[i].z(), 3) << ',';
    csv << fixed(r.per_vertex[i].fp, 6) << ',' << fixed(r.per_vertex[i].clearance_m, 2) << '\n';
  }
  return csv.str();
}

// Text for an XML element: its markup characters as entities.
std::string xml_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else out += c;
  }
  return out;
}

std::string kml_text(const PathReport& r, const std::vector<Vec3>& geo, const Wgs84Conversion& conversion) {
  const rt::PathMetrics& m = r.metrics;
  std::ostringstream kml;
  kml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>visvol " << r.objective << " path"
      << (r.requirements_met ? "" : ", requirements NOT MET") << "</name>\n<Placemark>\n<name>"
      << (r.requirements_met ? "" : "NOT MET: ") << "F_c " << fixed(m.fc, 4) << ", " << fixed(m.length_m / 1000.0, 2)
      << " km, clearance " << fixed(m.min_clearance_m, 0) << " m</name>\n"
      << "<description>Altitudes above mean sea level: the DEM's heights (orthometric, taken as EGM96). "
      << "Positions from the pack's CRS by " << xml_escaped(conversion.describe()) << '.';
  for (const std::string& u : r.unmet) kml << " Unmet: " << xml_escaped(u) << '.';
  kml << "</description>\n<LineString>\n<altitudeMode>absolute</altitudeMode>\n<coordinates>\n";
  for (const Vec3& g : geo) kml << fixed(g.x(), 8) << ',' << fixed(g.y(), 8) << ',' << fixed(g.z(), 2) << '\n';
  kml << "</coordinates>\n</LineString>\n</Placemark>\n</Document>\n</kml>\n";
  return kml.str();
}

// A SimpleItem; `altitude`: QGroundControl's altitude fields (absolute mode).
nlohmann::json mission_item(int jump_id, int command, int frame, const std::array<nlohmann::json, 7>& params,
                            bool altitude) {
  nlohmann::json item = {{"autoContinue", true}, {"command", command}, {"doJumpId", jump_id},
                         {"frame", frame},       {"params", params},   {"type", "SimpleItem"}};
  if (altitude) {
    item["AMSLAltAboveTerrain"] = nullptr;
    item["Altitude"] = params[6];
    item["AltitudeMode"] = qgc::kAltitudeModeAbsolute;
  }
  return item;
}

// The .plan: heights above mean sea level are the DEM's (orthometric).
nlohmann::json qgc_plan(const PathReport& r, const std::vector<Vec3>& geo) {
  using namespace mavlink;
  const bool fixed_wing = r.vehicle.type == rt::VehicleType::fixed_wing;
  const nlohmann::json no_yaw;  // NaN: the autopilot's default heading
  const Vec3 &start = geo.front(), &end = geo.back();
  nlohmann::json items = nlohmann::json::array();
  int id = 1;
  // takeoff at home to the first vertex's altitude (fixed-wing: climbing at
  // least its steepest climb, param 1, as PX4 and ArduPlane read it)
  const double takeoff_pitch_deg = fixed_wing ? r.vehicle.max_climb_deg : 0.0;
  items.push_back(mission_item(id++, kCmdNavTakeoff, kFrameGlobal,
                               {takeoff_pitch_deg, 0, 0, no_yaw, start.y(), start.x(), start.z()}, true));
  for (const Vec3& g : geo) {
    items.push_back(mission_item(id++, kCmdNavWaypoint, kFrameGlobal, {0, 0, 0, no_yaw, g.y(), g.x(), g.z()}, true));
  }
  if (fixed_wing) {
    // the landing sequence (an RTL with mission landing flies it too): circle
    // over the last vertex at its altitude, then land on the ground below it
    items.push_back(mission_item(id++, kCmdDoLandStart, kFrameGlobal, {0, 0, 0, 0, end.y(), end.x(), 0}, false));
    items.push_back(mission_item(id++, kCmdNavLoiterToAlt, kFrameGlobal,
                                 {0, r.vehicle.min_turn_radius_m, 0, 0, end.y(), end.x(), end.z()}, true));
  }
  items.push_back(
      mission_item(id++, kCmdNavLand, kFrameGlobal, {0, 0, 0, no_yaw, end.y(), end.x(), r.land_ground_m}, true));
  return {{"fileType", "Plan"},
          {"geoFence",
           {{"circles", nlohmann::json::array()},
            {"polygons", nlohmann::json::array()},
            {"version", qgc::kGeoFenceVersion}}},
          {"groundStation", "QGroundControl"},
          {"mission",
           {{"cruiseSpeed", r.vehicle.speed_m_per_s},
            {"firmwareType", r.vehicle.autopilot == rt::Autopilot::ardupilot ? kAutopilotArduPilotMega : kAutopilotPx4},
            {"globalPlanAltitudeMode", qgc::kAltitudeModeAbsolute},
            {"hoverSpeed", r.vehicle.speed_m_per_s},
            {"items", items},
            {"plannedHomePosition", {start.y(), start.x(), r.home_ground_m}},
            {"vehicleType", fixed_wing ? kTypeFixedWing : kTypeQuadrotor},
            {"version", qgc::kMissionVersion}}},
          {"rallyPoints", {{"points", nlohmann::json::array()}, {"version", qgc::kRallyPointsVersion}}},
          {"version", qgc::kPlanVersion}};
}

nlohmann::json geojson(const PathReport& r, const std::vector<Vec3>& geo, const Wgs84Conversion& conversion,
                       const GeoidShift& ellipsoidal) {
  const rt::PathMetrics& m = r.metrics;
  nlohmann::json props = {
      {"objective", r.objective},
      {"model", r.model},
      {"pack", r.pack},
      {"fc", m.fc},
      {"length_m", m.length_m},
      {"min_clearance_m", m.min_clearance_m},
      {"max_climb_deg", m.max_climb_deg},
      {"max_descent_deg", m.max_descent_deg},
      {"min_turn_radius_m",
       std::isfinite(m.min_turn_radius_m) ? nlohmann::json(m.min_turn_radius_m) : nlohmann::json()},
      {"height_reference",
       "coordinates: height above the WGS84 ellipsoid (RFC 7946); vertex_height_orthometric_m: "
       "the DEM's height (above mean sea level)"},
      {"vertical_datum", "WGS 84 ellipsoid (EPSG:4979)"},
      {"vertical_datum_source", kVerticalDatumSource},
      {"geoid_grid", ellipsoidal.grid},
      {"horizontal_transformation", conversion.operation},
      {"horizontal_accuracy_m", conversion.accuracy_m >= 0 ? nlohmann::json(conversion.accuracy_m) : nlohmann::json()},
      {"requirements_met", r.requirements_met},
      {"unmet", r.unmet}};
  nlohmann::json fp = nlohmann::json::array(), clearance = nlohmann::json::array(),
                 orthometric = nlohmann::json::array(), coords = nlohmann::json::array();
  for (std::size_t i = 0; i < geo.size(); ++i) {
    fp.push_back(r.per_vertex[i].fp);
    clearance.push_back(r.per_vertex[i].clearance_m);
    orthometric.push_back(geo[i].z());
    coords.push_back({geo[i].x(), geo[i].y(), ellipsoidal.points[i].z()});
  }
  props["vertex_fp"] = fp;
  props["vertex_clearance_m"] = clearance;
  props["vertex_height_orthometric_m"] = orthometric;
  return {{"type", "FeatureCollection"},
          {"features",
           {{{"type", "Feature"},
             {"geometry", {{"type", "LineString"}, {"coordinates", coords}}},
             {"properties", props}}}}};
}

}  // namespace

Status check_path_outputs(const std::string& base) {
  // -o /dev/null made /dev/null.csv and its siblings in /dev
  struct stat st {};
  if (::stat(base.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    return invalid_argument(base + " is " + (S_ISDIR(st.st_mode) ? "a directory" : "not a regular file") +
                            ": -o names the outputs' base (BASE.csv, BASE.kml, BASE.plan, BASE.geojson); for files "
                            "in a folder give FOLDER/NAME");
  }
  // -o /dev/stderr (a regular file when stderr is) made /dev/stderr.csv and
  // its siblings: no outputs among the devices or the kernel's files
  std::error_code ec;
  const std::filesystem::path folder =
      std::filesystem::weakly_canonical(std::filesystem::absolute(base, ec).parent_path(), ec);
  const std::string f = folder.string();
  const bool shared_memory = f == "/dev/shm" || f.rfind("/dev/shm/", 0) == 0;  // a scratch folder like /tmp
  for (const char* system : {"/dev", "/proc", "/sys"}) {
    if (!ec && !shared_memory && (f == system || f.rfind(std::string(system) + "/", 0) == 0)) {
      return invalid_argument(base + ": the outputs would go in " + f + ", a system folder: name a folder of yours");
    }
  }
  for (const char* extension : {".csv", ".kml", ".plan", ".geojson"}) {
    VISVOL_RETURN_IF_ERROR(check_output_path(base + extension));
  }
  return Status::ok_status();
}

namespace {

// Writes what it can of the set: the CSV whatever the CRS, the rest where
// the positions convert to WGS84 (and the geoid grid is there).
// What the set lacks, and why, as one status (the first reason's code).
Status not_written(const std::vector<std::pair<std::string, Status>>& missing,
                   const std::vector<std::string>& removed) {
  Status out;
  std::string text;
  for (const auto& [what, why] : missing) {
    if (why.ok()) continue;
    if (out.ok()) out = why;
    text += (text.empty() ? "" : "; ") + what + " not written: " + why.message();
  }
  if (out.ok()) return out;
  std::string gone;
  for (const std::string& f : removed) gone += (gone.empty() ? "" : ", ") + f;
  if (!gone.empty()) text += " (the earlier " + gone + " removed: another plan's)";
  return Status(out.code(), text);
}

}  // namespace

Status write_path_outputs(const std::string& base, const PathReport& r, std::vector<std::string>& written,
                          Wgs84Conversion* conversion_out) {
  VISVOL_RETURN_IF_ERROR(validate_report(r));
  Wgs84Conversion conversion;
  const Result<std::vector<Vec3>> geo = to_wgs84(r.vertices, r.crs_wkt, &conversion);
  if (conversion_out != nullptr) *conversion_out = conversion;
  const Result<GeoidShift> ellipsoidal =
      geo.ok() ? shift_heights(*geo, true) : Result<GeoidShift>(Status(Errc::unsupported, "no WGS84 positions"));
  Status plan_ground = check_plan_ground(r);
  if (plan_ground.ok() && !r.flyable) {
    // a crew loads the .plan into the autopilot: no mission into a hillside
    plan_ground = Status(Errc::state,
                         "the path breaks the vehicle's envelope or leaves the planning bounds, so it is no mission "
                         "for an autopilot (the other files are marked unmet)");
  }
  if (plan_ground.ok() && r.landing_loiter_clearance_m < r.vehicle.clearance_m - kHeightTolM) {
    // its approach circle into a hillside (a met path's mission did)
    char lowest[64] = "leaves the terrain the pack knows";
    if (std::isfinite(r.landing_loiter_clearance_m)) {
      std::snprintf(lowest, sizeof lowest, "comes to %.1f m over the ground", r.landing_loiter_clearance_m);
    }
    char text[320];
    std::snprintf(text, sizeof text,
                  "the landing's loiter circle (%.0f m around the last vertex at %.1f m) %s, under the %.1f m "
                  "clearance: no mission with that approach (another end, or a higher one)",
                  r.vehicle.min_turn_radius_m, r.vertices.back().z(), lowest, r.vehicle.clearance_m);
    plan_ground = Status(Errc::state, text);
  }
  // the set replaces the earlier one whole or not at all (a full disk left
  // the new CSV and KML beside no .plan); the earlier set's files this one
  // lacks go first, so that none of them is left beside it
  std::vector<std::pair<std::string, std::string>> set;
  set.emplace_back(base + ".csv", csv_text(r, geo, conversion, ellipsoidal));  // projected coordinates suffice
  if (geo.ok()) {
    set.emplace_back(base + ".kml", kml_text(r, *geo, conversion));
    if (plan_ground.ok()) set.emplace_back(base + ".plan", json_text(qgc_plan(r, *geo), 1) + "\n");
    if (ellipsoidal.ok()) {
      set.emplace_back(base + ".geojson", json_text(geojson(r, *geo, conversion, *ellipsoidal), 1) + "\n");
    }
  }
  std::vector<std::string> stale, removed;
  for (const char* extension : {".csv", ".kml", ".plan", ".geojson"}) {
    const std::string file = base + extension;
    if (std::none_of(set.begin(), set.end(), [&](const auto& f) { return f.first == file; })) stale.push_back(file);
  }
  if (Status w = write_files_atomically(set, stale, written, removed); !w.ok()) {
    return not_written({{"the set", w}}, removed);  // the earlier files removed are said too
  }
  if (!geo.ok()) return not_written({{"GeoJSON, KML and .plan", geo.status()}}, removed);
  return not_written({{".plan", plan_ground}, {"GeoJSON", ellipsoidal.status()}}, removed);
}

}  // namespace visvol::cli
