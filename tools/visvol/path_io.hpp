// Paths in and out of `visvol plan` (and into `visvol render`, `visvol check`).
//
// Heights. The DEM's heights are orthometric, taken as EGM96 (SRTM's datum;
// "above mean sea level" to an autopilot). Every output keeps them except the
// GeoJSON, whose third coordinate is, as RFC 7946 says, the height above the
// WGS84 ellipsoid: h = H + N, N the EGM96 geoid undulation at the vertex
// (PROJ, EPSG:4326+5773 to EPSG:4979, the grid us_nga_egm96_15.tif, formerly
// egm96_15.gtx, from Debian's proj-data). Without that grid the GeoJSON is not
// written (never orthometric heights labelled ellipsoidal), and a GeoJSON with
// heights is not read.
//
// In (read_path_file), four formats told apart by their content (a UTF-8
// byte order mark before any of them is skipped):
//   - text: points "x y" (lifted to the clearance above the terrain, densely,
//     as the paper's tracing tool does) or "x y z", in the pack's CRS;
//     separators are spaces, tabs or commas; '#' starts a comment; a first
//     line without digits is a header (one with digits that does not parse
//     is refused: a mistyped first point is never dropped);
//   - the CSV `visvol plan` writes: '#' comment lines, then a header naming
//     x_m, y_m and z_m (pack CRS, metres) and optionally fp; other columns
//     are ignored;
//   - GeoJSON: one LineString (bare, in a Feature or in a FeatureCollection),
//     RFC 7946 WGS84 longitude, latitude and optional ellipsoidal height,
//     converted to the pack's CRS with OGR and to orthometric heights with
//     PROJ (the reverse of the writer: a written path reads back to the same
//     points). A file written by visvol before heights were ellipsoidal (its
//     properties.height_reference says "the DEM's vertical datum (mean sea
//     level)") is read with its heights as they are. properties.vertex_fp,
//     when present, is the F_p of each vertex;
//   - a QGroundControl .plan (JSON with "fileType": "Plan", version 1): the
//     path is its waypoint, spline waypoint and loiter items in order (a
//     loiter at its centre; one over the waypoint before it adds nothing, so
//     a .plan `visvol plan` wrote reads back to its vertices); takeoff,
//     landing, return to launch and items that move nothing are not part of
//     it; an item that moves the aircraft otherwise (a jump, orbit, mode,
//     home or altitude change...), an unknown command and a ComplexItem
//     (survey, landing pattern, ...) are refused, their flown path not being
//     in the file. Frames: MAV_FRAME_GLOBAL
//     (0, and 5, its _INT twin: altitude above mean sea level, the DEM's
//     heights) and MAV_FRAME_GLOBAL_RELATIVE_ALT (3, and 6: above the planned
//     home position, whose altitude is added); any other frame (terrain
//     frame 10, local frames) is refused naming the item.
// Out (write_path_outputs): GeoJSON, CSV, KML and a QGroundControl .plan; see
// there.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "rt/rope/path_metrics.hpp"
#include "rt/rope/vehicle.hpp"
#include "wgs84.hpp"

namespace visvol::cli {

using rt::Vec3;

// MAVLink and QGroundControl numbers the .plan writer and reader use.
namespace mavlink {
inline constexpr int kCmdNavWaypoint = 16;            // MAV_CMD_NAV_WAYPOINT
inline constexpr int kCmdNavLoiterUnlim = 17;         // MAV_CMD_NAV_LOITER_UNLIM
inline constexpr int kCmdNavLoiterTurns = 18;         // MAV_CMD_NAV_LOITER_TURNS
inline constexpr int kCmdNavLoiterTime = 19;          // MAV_CMD_NAV_LOITER_TIME
inline constexpr int kCmdNavReturnToLaunch = 20;      // MAV_CMD_NAV_RETURN_TO_LAUNCH
inline constexpr int kCmdNavSplineWaypoint = 82;      // MAV_CMD_NAV_SPLINE_WAYPOINT
inline constexpr int kCmdNavVtolTakeoff = 84;         // MAV_CMD_NAV_VTOL_TAKEOFF
inline constexpr int kCmdNavVtolLand = 85;            // MAV_CMD_NAV_VTOL_LAND
inline constexpr int kCmdNavLand = 21;                // MAV_CMD_NAV_LAND
inline constexpr int kCmdNavTakeoff = 22;             // MAV_CMD_NAV_TAKEOFF
inline constexpr int kCmdNavLandLocal = 23;           // MAV_CMD_NAV_LAND_LOCAL
inline constexpr int kCmdNavLoiterToAlt = 31;         // MAV_CMD_NAV_LOITER_TO_ALT
inline constexpr int kCmdDoLandStart = 189;           // MAV_CMD_DO_LAND_START
inline constexpr int kFrameGlobal = 0;                // MAV_FRAME_GLOBAL: altitude above mean sea level
inline constexpr int kFrameGlobalRelativeAlt = 3;     // MAV_FRAME_GLOBAL_RELATIVE_ALT: above home
inline constexpr int kFrameGlobalInt = 5;             // MAV_FRAME_GLOBAL_INT (deprecated twin of 0)
inline constexpr int kFrameGlobalRelativeAltInt = 6;  // MAV_FRAME_GLOBAL_RELATIVE_ALT_INT (twin of 3)
inline constexpr int kFrameGlobalTerrainAlt = 10;     // MAV_FRAME_GLOBAL_TERRAIN_ALT: above the terrain
inline constexpr int kAutopilotArduPilotMega = 3;     // MAV_AUTOPILOT_ARDUPILOTMEGA
inline constexpr int kAutopilotPx4 = 12;              // MAV_AUTOPILOT_PX4
inline constexpr int kTypeFixedWing = 1;              // MAV_TYPE_FIXED_WING
inline constexpr int kTypeQuadrotor = 2;              // MAV_TYPE_QUADROTOR
}  // namespace mavlink
namespace qgc {
inline constexpr int kPlanVersion = 1;           // the file's "version"
inline constexpr int kMissionVersion = 2;        // mission.version
inline constexpr int kGeoFenceVersion = 2;       // geoFence.version
inline constexpr int kRallyPointsVersion = 2;    // rallyPoints.version
inline constexpr int kAltitudeModeAbsolute = 2;  // QGroundControl's AltMode: MAV_FRAME_GLOBAL
}  // namespace qgc

enum class PathFormat { text, plan_csv, geojson, qgc_plan };

// A .plan's loiter item (MAV_CMD_NAV_LOITER_*) as the file gives it; `check`
// flies it as a circle (flown_path.hpp).
enum class LoiterKind : std::uint8_t {
  unlimited,   // 17: until the operator moves the aircraft on (flown as one turn)
  turns,       // 18: `amount` turns
  time,        // 19: `amount` seconds
  to_altitude  // 31: until its altitude is reached
};
struct LoiterItem {
  std::size_t vertex = 0;      // in PathFile::points: the loiter's centre, or the waypoint it circles over
  bool over_waypoint = false;  // centred on the waypoint before it: the aircraft flies over it, then circles
  double altitude_m = 0;       // the circle's altitude (the DEM's datum)
  double radius_m = 0;         // > 0 clockwise, < 0 counter-clockwise, 0 the autopilot's own radius
  LoiterKind kind = LoiterKind::unlimited;
  double amount = 0;  // turns (LoiterKind::turns) or seconds (LoiterKind::time)
  std::string item;   // "mission.items[5]", for reports
};

struct PathFile {
  std::vector<Vec3> points;  // pack CRS, metres (z: the DEM's datum, 0 without heights)
  bool has_heights = false;  // every point has a z
  std::vector<double> fp;    // F_p per point from the file (plan CSV, GeoJSON), or empty
  PathFormat format = PathFormat::text;
  // .plan: the loiters, in mission order. A LOITER_TO_ALT over the last
  // waypoint, at its altitude, that a landing follows is the landing's
  // approach and is not among them.
  std::vector<LoiterItem> loiters;
  // .plan: those approach loiters, which a check does not fly (it says so)
  std::vector<LoiterItem> approach;
  // What the file says of itself (visvol plan's CSV '# requirements:' lines,
  // its GeoJSON's requirements_met): unset where it says nothing.
  std::optional<bool> requirements_met;
  // .plan: what the reader noticed of the mission that a check should say
  // (a takeoff's leg added, a landing away from the path)
  std::vector<std::string> notes;
  // .plan: per point, the seconds a waypoint's param 1 holds a multirotor
  // there (0 for a loiter's point); empty for the other formats
  std::vector<double> hold_s;
  // .plan: what the mission states of its vehicle (absent where it does not)
  std::optional<double> cruise_speed_m_per_s, hover_speed_m_per_s;
  int vehicle_type = -1;       // MAV_TYPE (1 fixed wing, 2 quadrotor...)
  int firmware_type = -1;      // MAV_AUTOPILOT (3 ArduPilot, 12 PX4), -1 not given
  bool speed_changes = false;  // DO_CHANGE_SPEED items: the speed differs along the way
  // the largest acceptance radius its waypoints ask for (param 2, m): an
  // autopilot takes them at least that early; absent where all are 0
  std::optional<double> acceptance_radius_m;
  // .plan with altitudes above home: the planned home (pack CRS, altitude
  // above mean sea level) they were lifted by
  std::optional<Vec3> relative_home;
};
// At least 2 points, all finite, not all at one spot (within 1 cm), numbers
// in decimal (text and CSV: no hexadecimal, inf or nan). crs_wkt is the pack's CRS: a GeoJSON or
// .plan path needs it (an error names the file otherwise); the other formats
// ignore it. Errors name the file and the line (or the JSON member, or the
// .plan's item index) and the problem.
Result<PathFile> read_path_file(const std::string& path, const std::string& crs_wkt = {});

// A 2D polyline lifted to `clearance_m` above the terrain, sampled every `step_m`.
std::vector<Vec3> lift_polyline(const std::vector<Vec3>& points_2d, double clearance_m, double step_m,
                                const std::function<double(double, double)>& terrain_height);

struct VertexInfo {
  double fp = 0;           // F_p at the vertex
  double clearance_m = 0;  // height above the terrain
};

struct PathReport {
  std::vector<Vec3> vertices;          // pack CRS, metres
  std::vector<VertexInfo> per_vertex;  // one per vertex
  rt::PathMetrics metrics;
  std::string objective, model, pack, crs_wkt;
  // Terrain heights (the DEM's datum) below the first and the last vertex:
  // the .plan's home and landing point. Required (finite); a .plan also needs
  // each not above its vertex.
  double home_ground_m = std::numeric_limits<double>::quiet_NaN();
  double land_ground_m = std::numeric_limits<double>::quiet_NaN();
  rt::VehicleEnvelope vehicle;  // the .plan's firmware, vehicle type, speeds, takeoff pitch, loiter radius
  // The exact check's verdict (rt::PathCheck), written into the GeoJSON's
  // properties so that a path that breaks a requirement says so where it goes.
  bool requirements_met = true;
  std::vector<std::string> unmet;
  // The vehicle's envelope and the planning bounds hold (rt::PathCheck's
  // flight_violation is 0): only then is a .plan, the mission an autopilot
  // flies, written.
  bool flyable = true;
  // A fixed-wing .plan's landing circles over the last vertex at its altitude
  // (min-turn-radius): the circle's least height above the finest terrain
  // (-infinity where it leaves the terrain the pack knows; NaN: not computed,
  // no circle). Under the vehicle's clearance, no .plan is written.
  double landing_loiter_clearance_m = std::numeric_limits<double>::quiet_NaN();
};

// The GeoJSON's properties.vertical_datum_source.
inline constexpr const char* kVerticalDatumSource = "EGM96 (DEM heights taken as EGM96 orthometric)";

// Writes the set, replacing an earlier one whole or not at all (a full disk
// leaves the earlier set as it was), `written` listing them:
//   BASE.csv: '#' lines naming the CRS and datums, a header row, one row per
//     vertex: index, x_m, y_m, z_m (pack CRS; z orthometric, the DEM's),
//     lon_deg, lat_deg (WGS84), h_ellipsoidal_m (WGS84 ellipsoid), fp,
//     clearance_m;
//   BASE.kml: a LineString, altitudeMode absolute (orthometric heights);
//   BASE.plan: a QGroundControl mission (MAV_FRAME_GLOBAL, altitudes above
//     mean sea level): planned home on the ground below the first vertex,
//     NAV_TAKEOFF there to the first vertex's altitude, a NAV_WAYPOINT per
//     vertex; then a multirotor lands (NAV_LAND) on the ground below the last
//     vertex; a fixed-wing aircraft gets DO_LAND_START, NAV_LOITER_TO_ALT
//     over the last vertex at its altitude (radius: its turn radius) and
//     NAV_LAND on the ground below it (the approach from the loiter down is
//     the autopilot's: visvol knows no runway);
//   BASE.geojson: RFC 7946 LineString (longitude, latitude, ellipsoidal
//     height) with the metrics, the datums and per-vertex F_p, clearance and
//     orthometric height as properties.
// A report that does not hold together (sizes, non-finite values, vehicle,
// ground heights not set) writes nothing (Errc::invalid_argument). Without a
// CRS only the CSV is written and the status says why the others are not;
// without the geoid grid all but the GeoJSON are (and the CSV has no
// h_ellipsoidal_m), and the status names the grid; a path whose first or last
// vertex is below its ground height gets no .plan, nor one that is not
// `flyable`, nor one whose landing circle comes under the clearance
// (landing_loiter_clearance_m), and the status says so (Errc::state); an
// earlier plan's .plan under BASE is then removed. The CSV's '#' lines and the KML's name say
// whether every requirement is met, and name what is not.
// `conversion`, where given, gets how the positions reached WGS84.
Status write_path_outputs(const std::string& base, const PathReport& report, std::vector<std::string>& written,
                          Wgs84Conversion* conversion = nullptr);

// What write_path_outputs would refuse about its four file names (an existing
// symlink, device, FIFO or directory, no such directory), checked before the
// planning so that a bad -o costs nothing.
Status check_path_outputs(const std::string& base);

}  // namespace visvol::cli
