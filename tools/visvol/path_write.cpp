// Writing a path's four files (path_io.hpp: write_path_outputs) and
// checking their names first.
#include "path_io.hpp"

#include <ogr_spatialref.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "base/tolerances.hpp"
#include "io/atomic_file.hpp"
#include "io/json_text.hpp"
#include "path_io_detail.hpp"

namespace visvol::cli {

using detail::fixed;

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
  // param 2, the acceptance radius at cruise speed, as the user gave it (the
  // check takes a PX4 fixed-wing's that much farther out in --max-wind:
  // rt::switch_distance_m; 0, a multirotor's: the autopilot's own)
  const double accept_m = r.vehicle.acceptance_radius_m;
  for (const Vec3& g : geo) {
    items.push_back(
        mission_item(id++, kCmdNavWaypoint, kFrameGlobal, {0, accept_m, 0, no_yaw, g.y(), g.x(), g.z()}, true));
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
