// The QGroundControl .plan reader: the items the aircraft flies to, in
// order, and the loiters it circles (see path_io.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>

#include "path_io_detail.hpp"

namespace visvol::cli::detail {

namespace {

const char* frame_name(int frame) {
  switch (frame) {
    case mavlink::kFrameGlobal: return "MAV_FRAME_GLOBAL";
    case 1: return "MAV_FRAME_LOCAL_NED";
    case 2: return "MAV_FRAME_MISSION";
    case mavlink::kFrameGlobalRelativeAlt: return "MAV_FRAME_GLOBAL_RELATIVE_ALT";
    case 4: return "MAV_FRAME_LOCAL_ENU";
    case mavlink::kFrameGlobalInt: return "MAV_FRAME_GLOBAL_INT";
    case mavlink::kFrameGlobalRelativeAltInt: return "MAV_FRAME_GLOBAL_RELATIVE_ALT_INT";
    case mavlink::kFrameGlobalTerrainAlt: return "MAV_FRAME_GLOBAL_TERRAIN_ALT, above the terrain";
    case 11: return "MAV_FRAME_GLOBAL_TERRAIN_ALT_INT, above the terrain";
    default: return "not a global frame";
  }
}

// A JSON number with an integer value (QGroundControl writes integers; 16.0 is 16).
bool integer_of(const nlohmann::json& j, long long& v) {
  if (j.is_number_integer()) {
    v = j.get<long long>();
    return true;
  }
  if (!j.is_number_float()) return false;
  const double d = j.get<double>();
  if (!std::isfinite(d) || d != std::floor(d) || std::fabs(d) > 1e15) return false;
  v = static_cast<long long>(d);
  return true;
}

// mission.plannedHomePosition: [latitude, longitude, altitude above mean sea level].
// The planned home: longitude, latitude, altitude (above mean sea level).
Status read_home(const nlohmann::json& mission, const std::string& where, Vec3& lon_lat_alt) {
  const auto it = mission.find("plannedHomePosition");
  if (it == mission.end() || !it->is_array() || it->size() != 3) {
    return invalid_argument(where + "mission.plannedHomePosition is missing or not [latitude, longitude, altitude]");
  }
  for (std::size_t k = 0; k < 3; ++k) {
    if (!(*it)[k].is_number() || !std::isfinite((*it)[k].get<double>())) {
      return invalid_argument(where + "mission.plannedHomePosition[" + std::to_string(k) + "] " + json_brief((*it)[k]) +
                              " is not a finite number");
    }
  }
  const double lat = (*it)[0].get<double>(), lon = (*it)[1].get<double>();
  if (std::fabs(lat) > 90 || std::fabs(lon) > 180) {
    return invalid_argument(where + "mission.plannedHomePosition (" + shown(lat, 6) + ", " + shown(lon, 6) +
                            ") is not a WGS84 latitude and longitude in degrees");
  }
  lon_lat_alt = {lon, lat, (*it)[2].get<double>()};
  return Status::ok_status();
}

// A speed the mission states (cruiseSpeed, hoverSpeed): none when absent or
// null, a speed in [0.1, 1000] m/s (a vehicle's range) otherwise.
Result<std::optional<double>> read_speed(const nlohmann::json& mission, const char* key, const std::string& file) {
  const auto it = mission.find(key);
  if (it == mission.end() || it->is_null()) return std::optional<double>();
  if (!it->is_number() || !(it->get<double>() >= 0.1 && it->get<double>() <= 1000)) {
    return invalid_argument(file + "mission." + key + " " + json_brief(*it) + " is not a speed in [0.1, 1000] m/s");
  }
  return std::optional<double>(it->get<double>());
}

constexpr long long kCmdDoChangeSpeed = 178;  // MAV_CMD_DO_CHANGE_SPEED: moves nothing, noted

// What a mission item is to the flown path, by its MAV_CMD number.
enum class ItemRole : std::uint8_t {
  vertex,     // flown at its position: a vertex of the path
  end,        // takeoff, landing, return to launch: the mission's ends, not checked
  no_motion,  // moves nothing (conditions, camera, gimbal, speed, ROI...)
  moves,      // moves the aircraft along what visvol cannot read from the file
  unknown,    // none visvol knows to leave the path unchanged: it may move the aircraft
};

// Commands that leave the flown path as it is: conditions that
// hold the aircraft on it, speed, camera, gimbal, servo, relay and ROI
// commands. A list of those visvol knows (MAVLink's common set): any other
// command may move the aircraft (a jump, a mode or home change, a
// termination, an orbit...), and a path read past it would not be the path
// flown.
bool leaves_path_unchanged(long long command) {
  constexpr long long kNavRoi = 80;
  constexpr long long kConditionDelay = 112, kConditionDistance = 114, kConditionYaw = 115;
  constexpr long long kDoSetRelay = 181, kDoRepeatRelay = 182, kDoSetServo = 183;
  constexpr long long kDoRepeatServo = 184, kDoSetActuator = 187;
  constexpr long long kDoSetRoiLocation = 195, kDoSetRoiWpnextOffset = 196, kDoSetRoiNone = 197;
  constexpr long long kDoSetRoiSysid = 198, kDoControlVideo = 200, kDoSetRoi = 201, kDoDigicamConfigure = 202;
  constexpr long long kDoDigicamControl = 203, kDoMountConfigure = 204, kDoMountControl = 205;
  constexpr long long kDoSetCamTriggDist = 206, kDoFenceEnable = 207, kDoGripper = 211;
  constexpr long long kDoSetCamTriggInterval = 214, kDoMountControlQuat = 220, kObliqueSurvey = 260;
  constexpr long long kSetCameraMode = 530, kSetCameraZoom = 531, kSetCameraFocus = 532;
  constexpr long long kGimbalManagerPitchyaw = 1000, kGimbalManagerConfigure = 1001;
  constexpr long long kImageStartCapture = 2000, kImageStopCapture = 2001, kDoTriggerControl = 2003;
  constexpr long long kCameraTrackPoint = 2004, kCameraTrackRectangle = 2005, kCameraStopTracking = 2010;
  constexpr long long kVideoStartCapture = 2500, kVideoStopCapture = 2501, kVideoStartStreaming = 2502;
  constexpr long long kVideoStopStreaming = 2503;
  switch (command) {
    case kNavRoi:
    case kConditionDelay:
    case kConditionDistance:
    case kConditionYaw:
    case kCmdDoChangeSpeed:
    case kDoSetRelay:
    case kDoRepeatRelay:
    case kDoSetServo:
    case kDoRepeatServo:
    case kDoSetActuator:
    case mavlink::kCmdDoLandStart:  // a marker for a landing sequence
    case kDoSetRoiLocation:
    case kDoSetRoiWpnextOffset:
    case kDoSetRoiNone:
    case kDoSetRoiSysid:
    case kDoControlVideo:
    case kDoSetRoi:
    case kDoDigicamConfigure:
    case kDoDigicamControl:
    case kDoMountConfigure:
    case kDoMountControl:
    case kDoSetCamTriggDist:
    case kDoFenceEnable:
    case kDoGripper:
    case kDoSetCamTriggInterval:
    case kDoMountControlQuat:
    case kObliqueSurvey:
    case kSetCameraMode:
    case kSetCameraZoom:
    case kSetCameraFocus:
    case kGimbalManagerPitchyaw:
    case kGimbalManagerConfigure:
    case kImageStartCapture:
    case kImageStopCapture:
    case kDoTriggerControl:
    case kCameraTrackPoint:
    case kCameraTrackRectangle:
    case kCameraStopTracking:
    case kVideoStartCapture:
    case kVideoStopCapture:
    case kVideoStartStreaming:
    case kVideoStopStreaming: return true;
    default: return false;
  }
}

// Commands known to move the aircraft along what the file does not hold
// (named so in the refusal; others are refused as unknown).
bool moves_off_the_file(long long command) {
  constexpr long long kNavFollow = 25, kContinueAndChangeAlt = 30, kDoFollow = 32, kDoFollowReposition = 33;
  constexpr long long kDoOrbit = 34, kNavPathPlanning = 81, kNavGuidedEnable = 92, kNavPayloadPlace = 94;
  constexpr long long kNavDelay = 93;  // a fixed-wing circles while it waits, on a circle the file does not give
  constexpr long long kConditionChangeAlt = 113, kDoSetMode = 176, kDoJump = 177, kDoSetHome = 179;
  constexpr long long kDoFlightTermination = 185, kDoChangeAltitude = 186, kDoReturnPathStart = 188;
  constexpr long long kDoRallyLand = 190, kDoGoAround = 191, kDoReposition = 192, kDoPauseContinue = 193;
  constexpr long long kDoSetReverse = 194, kDoParachute = 208, kDoInvertedFlight = 210, kDoAutotuneEnable = 212;
  constexpr long long kNavSetYawSpeed = 213, kDoGuidedLimits = 222, kDoEngineControl = 223;
  constexpr long long kDoSetMissionCurrent = 224, kComponentArmDisarm = 400, kDoJumpTag = 601;
  constexpr long long kDoVtolTransition = 3000, kNavScriptTime = 42702, kNavAttitudeTime = 42703;
  constexpr long long kFirstUserWaypoint = 31000, kLastUserSpatial = 31009;
  switch (command) {
    case kNavFollow:
    case kContinueAndChangeAlt:
    case kDoFollow:
    case kDoFollowReposition:
    case kDoOrbit:
    case kNavPathPlanning:
    case kNavGuidedEnable:
    case kNavPayloadPlace:
    case kNavDelay:
    case kConditionChangeAlt:
    case kDoSetMode:
    case kDoJump:
    case kDoSetHome:
    case kDoFlightTermination:
    case kDoChangeAltitude:
    case kDoReturnPathStart:
    case kDoRallyLand:
    case kDoGoAround:
    case kDoReposition:
    case kDoPauseContinue:
    case kDoSetReverse:
    case kDoParachute:
    case kDoInvertedFlight:
    case kDoAutotuneEnable:
    case kNavSetYawSpeed:
    case kDoGuidedLimits:
    case kDoEngineControl:
    case kDoSetMissionCurrent:
    case kComponentArmDisarm:
    case kDoJumpTag:
    case kDoVtolTransition:
    case kNavScriptTime:
    case kNavAttitudeTime: return true;
    default: return command >= kFirstUserWaypoint && command <= kLastUserSpatial;  // user commands with positions
  }
}

constexpr long long kTakeoffLocal = 24;  // MAV_CMD_NAV_TAKEOFF_LOCAL

ItemRole item_role(long long command) {
  using namespace mavlink;
  switch (command) {
    case kCmdNavWaypoint:
    case kCmdNavLoiterUnlim:
    case kCmdNavLoiterTurns:
    case kCmdNavLoiterTime:
    case kCmdNavLoiterToAlt: return ItemRole::vertex;
    case kCmdNavReturnToLaunch:
    case kCmdNavLand:
    case kCmdNavTakeoff:
    case kCmdNavLandLocal:
    case kTakeoffLocal:
    case kCmdNavVtolTakeoff:
    case kCmdNavVtolLand: return ItemRole::end;
    default: break;
  }
  if (leaves_path_unchanged(command)) return ItemRole::no_motion;
  return moves_off_the_file(command) ? ItemRole::moves : ItemRole::unknown;
}

// A loiter's parameter (params[index]): a finite number in [lo, hi]; null
// (QGroundControl's NaN) is `if_null` where that is allowed (not NaN).
Result<double> loiter_param(const nlohmann::json& params, std::size_t index, const char* name, double lo, double hi,
                            double if_null, const std::string& where) {
  const nlohmann::json& p = params[index];
  if (p.is_null() && !std::isnan(if_null)) return if_null;
  if (!p.is_number() || !std::isfinite(p.get<double>()) || p.get<double>() < lo || p.get<double>() > hi) {
    return invalid_argument(where + "params[" + std::to_string(index) + "] (" + name + ") " + json_brief(p) +
                            " is not a number in " + shown(lo, 0) + ".." + shown(hi, 0));
  }
  return p.get<double>();
}

// What a loiter item says of its circle (MAVLink's parameters: turns or
// seconds first, the radius third; LOITER_TO_ALT's radius second).
Result<LoiterItem> read_loiter(long long command, const nlohmann::json& params, const std::string& where) {
  constexpr double kMaxRadiusM = 1e5, kMaxTurns = 1000, kMaxSeconds = 1e6;
  LoiterItem l;
  const std::size_t radius_index = command == mavlink::kCmdNavLoiterToAlt ? 1 : 2;
  Result<double> radius = loiter_param(params, radius_index, "radius, m", -kMaxRadiusM, kMaxRadiusM, 0.0, where);
  if (!radius.ok()) return radius.status();
  l.radius_m = *radius;
  const double no_default = std::nan("");
  if (command == mavlink::kCmdNavLoiterTurns) {
    Result<double> turns = loiter_param(params, 0, "turns", 0, kMaxTurns, no_default, where);
    if (!turns.ok()) return turns.status();
    l.kind = LoiterKind::turns;
    l.amount = *turns;
  } else if (command == mavlink::kCmdNavLoiterTime) {
    Result<double> seconds = loiter_param(params, 0, "time, s", 0, kMaxSeconds, no_default, where);
    if (!seconds.ok()) return seconds.status();
    l.kind = LoiterKind::time;
    l.amount = *seconds;
  } else {
    l.kind = command == mavlink::kCmdNavLoiterToAlt ? LoiterKind::to_altitude : LoiterKind::unlimited;
  }
  return l;
}

// Beyond this, a takeoff's or landing's number is no height or degree.
constexpr double kMaxEndAltitudeM = 1e5;

// What a position item holds, each checked as every such item's is:
// params[4..6], its frame, a latitude and longitude in range.
constexpr std::array<const char*, 3> kPositionNames = {"latitude", "longitude", "altitude"};

Status check_params(const nlohmann::json& item, const std::string& where) {
  if (!item.contains("params") || !item["params"].is_array() || item["params"].size() != 7) {
    return invalid_argument(where + "params is missing or not an array of 7");
  }
  return Status::ok_status();
}

Result<long long> item_frame(const nlohmann::json& item, const std::string& where) {
  long long frame = 0;
  if (!item.contains("frame") || !integer_of(item["frame"], frame)) {
    return invalid_argument(where + "frame " + (item.contains("frame") ? json_brief(item["frame"]) : "missing") +
                            " is not an integer");
  }
  return frame;
}

Status check_wgs84(double lat, double lon, const std::string& where) {
  if (std::fabs(lat) > 90 || std::fabs(lon) > 180) {
    return invalid_argument(where + "latitude " + shown(lat, 6) + ", longitude " + shown(lon, 6) +
                            " is not a WGS84 position in degrees");
  }
  return Status::ok_status();
}

bool is_takeoff(long long command) {
  return command == mavlink::kCmdNavTakeoff || command == mavlink::kCmdNavVtolTakeoff || command == kTakeoffLocal;
}

// An end item's position, where it gives one: not 0, 0 or null ("where the
// aircraft is"). Longitude, latitude in degrees.
Result<std::optional<Vec3>> end_position(const nlohmann::json& item, long long command, const std::string& where) {
  if (command == kTakeoffLocal || command == mavlink::kCmdNavLandLocal) {
    return invalid_argument(where + "command " + std::to_string(command) +
                            " (a takeoff or landing in local metres): local frames are not read; use 22 or 21");
  }
  // checked as a waypoint's are: a landing's or takeoff's numbers that mean
  // nothing were left unread (a string latitude, altitude 1e308, frame 99)
  VISVOL_RETURN_IF_ERROR(check_params(item, where));
  const nlohmann::json& params = item["params"];
  for (std::size_t k = 0; k < 3; ++k) {
    const nlohmann::json& p = params[4 + k];
    if (p.is_null()) continue;
    if (!p.is_number() || !std::isfinite(p.get<double>()) || std::fabs(p.get<double>()) > kMaxEndAltitudeM) {
      return invalid_argument(where + "params[" + std::to_string(4 + k) + "] (" + kPositionNames[k] + ") " +
                              json_brief(p) + " is not a number within +-" + shown(kMaxEndAltitudeM, 0) + " (or null)");
    }
  }
  Result<long long> frame_read = item_frame(item, where);
  if (!frame_read.ok()) return frame_read.status();
  const long long frame = *frame_read;
  const nlohmann::json& lat = params[4];
  const nlohmann::json& lon = params[5];
  if (lat.is_null() || lon.is_null()) return std::optional<Vec3>();  // where the aircraft is
  const double la = lat.get<double>(), lo = lon.get<double>();
  if (la == 0 && lo == 0) return std::optional<Vec3>();
  VISVOL_RETURN_IF_ERROR(check_wgs84(la, lo, where));
  if (frame != mavlink::kFrameGlobal && frame != mavlink::kFrameGlobalInt &&
      frame != mavlink::kFrameGlobalRelativeAlt && frame != mavlink::kFrameGlobalRelativeAltInt) {
    return invalid_argument(where + "frame " + std::to_string(frame) + " (" +
                            frame_name(frame >= 0 && frame < 64 ? static_cast<int>(frame) : -1) +
                            ") is not supported for a position; frame 0 or 3");
  }
  return std::optional<Vec3>(Vec3(lo, la, 0));
}

// Metres between two longitude, latitude points a few kilometres apart at
// most where it matters (equirectangular; longitudes across 180 wrapped).
double apart_m(const Vec3& a, const Vec3& b) {
  constexpr double kMetresPerDegree = 111320.0, kRadPerDeg = 0.017453292519943295;
  double dlon = a.x() - b.x();
  if (dlon > 180) dlon -= 360;
  if (dlon < -180) dlon += 360;
  const double east = dlon * kMetresPerDegree * std::cos(0.5 * (a.y() + b.y()) * kRadPerDeg);
  return std::hypot(east, (a.y() - b.y()) * kMetresPerDegree);
}

// A takeoff or landing this near the first or last waypoint is on its spot:
// the climb or descent there is the mission's end, not its path.
constexpr double kEndOnTheSpotM = 5.0;

}  // namespace

// The waypoints of a QGroundControl .plan (a takeoff's point away from the
// first, waypoints and loiters, a loiter at its centre, or none over the
// waypoint before it) and its loiters, to the pack's CRS.
Result<PathFile> parse_qgc_plan(const nlohmann::json& j, const std::string& path, const std::string& crs_wkt) {
  const std::string file = path + ": ";
  if (!j["fileType"].is_string() || j["fileType"].get<std::string>() != "Plan") {
    return invalid_argument(file + "fileType " + json_brief(j["fileType"]) + "; a QGroundControl plan has \"Plan\"");
  }
  long long version = 0;
  if (!j.contains("version") || !integer_of(j["version"], version) || version != qgc::kPlanVersion) {
    return invalid_argument(file + "version " + (j.contains("version") ? json_brief(j["version"]) : "missing") +
                            "; this reader knows QGroundControl plan version " + std::to_string(qgc::kPlanVersion));
  }
  if (!j.contains("mission") || !j["mission"].is_object()) return invalid_argument(file + "no mission object");
  const nlohmann::json& mission = j["mission"];
  if (!mission.contains("items") || !mission["items"].is_array()) {
    return invalid_argument(file + "mission.items is missing or not an array");
  }
  const nlohmann::json& items = mission["items"];
  PathFile out;
  out.format = PathFormat::qgc_plan;
  out.has_heights = true;
  std::optional<Vec3> home;         // longitude, latitude, altitude, once an item needs it
  std::string end_after_waypoints;  // an end item read after a waypoint (where, command), or empty
  std::string unlimited_loiter;     // where an unlimited loiter was read, or empty
  // A takeoff with a position starts the path at its point and altitude (the
  // leg to the first waypoint is flown: QGroundControl puts a multirotor's
  // takeoff at home, a fixed-wing's ahead of it); on the first waypoint's
  // spot it is dropped. Where it was read, while it waits for that waypoint.
  std::string takeoff_where;
  std::optional<Vec3> landing;  // the last landing's position, where it gives one
  std::string landing_where;
  std::string return_where;    // a return to launch after the waypoints
  bool waypoint_read = false;  // a waypoint or loiter (not a takeoff's point) read
  bool landing_after_waypoints = false;
  for (const auto& [key, speed] :
       {std::pair{"cruiseSpeed", &out.cruise_speed_m_per_s}, std::pair{"hoverSpeed", &out.hover_speed_m_per_s}}) {
    Result<std::optional<double>> read = read_speed(mission, key, file);
    if (!read.ok()) return read.status();
    *speed = *read;
  }
  long long firmware_type = 0;
  if (mission.contains("firmwareType") && integer_of(mission["firmwareType"], firmware_type) && firmware_type >= 0 &&
      firmware_type < 1000) {
    out.firmware_type = static_cast<int>(firmware_type);
  }
  long long vehicle_type = 0;
  if (mission.contains("vehicleType") && integer_of(mission["vehicleType"], vehicle_type) && vehicle_type >= 0 &&
      vehicle_type < 1000) {
    out.vehicle_type = static_cast<int>(vehicle_type);
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const nlohmann::json& item = items[i];
    std::string where = file + "mission.items[" + std::to_string(i) + "]";
    long long jump_id = 0;
    if (item.is_object() && item.contains("doJumpId") && integer_of(item["doJumpId"], jump_id)) {
      where += " (doJumpId " + std::to_string(jump_id) + ")";
    }
    where += ": ";
    if (!item.is_object() || !item.contains("type") || !item["type"].is_string()) {
      return invalid_argument(where + "not a mission item (an object with a type)");
    }
    const std::string type = item["type"].get<std::string>();
    if (type == "ComplexItem") {
      const std::string kind = item.contains("complexItemType") && item["complexItemType"].is_string()
                                   ? item["complexItemType"].get<std::string>()
                                   : std::string("of no complexItemType");
      return invalid_argument(where + "a ComplexItem (" + kind +
                              "): its flown path is not in the file; only SimpleItems are read");
    }
    if (type != "SimpleItem") return invalid_argument(where + "type '" + quoted(type) + "' is not SimpleItem");
    long long command = 0;
    if (!item.contains("command") || !integer_of(item["command"], command)) {
      const std::string given = item.contains("command") ? json_brief(item["command"]) : "missing";
      return invalid_argument(where + "command " + given + " is not an integer");
    }
    if (command == mavlink::kCmdNavSplineWaypoint) {
      // judged as straight legs, it read as met where the curve flown passed
      // 157 m off them and 22 m under the clearance
      return invalid_argument(where +
                              "command 82 (a spline waypoint): the autopilot flies a curve through it that "
                              "the file does not give, away from the straight legs a check would judge; "
                              "write the mission with waypoints (16), or check the path as flown");
    }
    const ItemRole role = item_role(command);
    if (role == ItemRole::moves || role == ItemRole::unknown) {
      return invalid_argument(where + "command " + std::to_string(command) +
                              (role == ItemRole::moves
                                   ? " moves the aircraft along a path visvol cannot read from the file (a jump, "
                                     "orbit, follow, termination, mode, home or altitude change...)"
                                   : " is not a command visvol knows to leave the flown path unchanged (speed, "
                                     "camera, gimbal, servo, relay, ROI, conditions), and it may move the aircraft") +
                              "; the path is read from waypoints (16) and loiters (17, 18, 19, 31): write the mission "
                              "with those, or check the path as flown");
    }
    // a takeoff, landing or return between waypoints flies legs that are not
    // in the file (home and back, a climb out): the path read would skip them
    if (role == ItemRole::end && waypoint_read) {
      end_after_waypoints = where + "command " + std::to_string(command);
      landing_after_waypoints = landing_after_waypoints || command == mavlink::kCmdNavLand ||
                                command == mavlink::kCmdNavVtolLand || command == mavlink::kCmdNavLandLocal;
    }
    if (role == ItemRole::end && !waypoint_read && command != mavlink::kCmdNavTakeoff &&
        command != mavlink::kCmdNavVtolTakeoff && command != kTakeoffLocal) {
      // a landing or a return first: the mission ends there
      return invalid_argument(where + "command " + std::to_string(command) +
                              " (a landing or return to launch) comes before the first waypoint: the mission ends "
                              "there, and the waypoints after it are never flown");
    }
    bool takeoff_point = false;
    std::optional<Vec3> takeoff_home;  // a takeoff "where the aircraft is": the planned home, if known
    if (role == ItemRole::end) {
      Result<std::optional<Vec3>> at = end_position(item, command, where);
      if (!at.ok()) return at.status();
      if (is_takeoff(command) && out.points.empty() && !waypoint_read && !at->has_value() &&
          item["params"][6].is_number()) {
        Vec3 planned;
        if (read_home(mission, where, planned).ok()) takeoff_home = planned;
      }
      takeoff_point = is_takeoff(command) && out.points.empty() && !waypoint_read && (at->has_value() || takeoff_home);
      if (!is_takeoff(command) && at->has_value()) {
        landing = **at;
        landing_where = where;
      }
      if (command == mavlink::kCmdNavReturnToLaunch && waypoint_read) return_where = where;
    }
    if (command == kCmdDoChangeSpeed) out.speed_changes = true;
    if (role != ItemRole::vertex && !takeoff_point) continue;  // landing, DO_...: not the path
    if (!unlimited_loiter.empty()) {
      return invalid_argument(unlimited_loiter +
                              "command 17 (an unlimited loiter) comes before this waypoint: the aircraft circles "
                              "there until told otherwise, and never flies on; put it last, or give it turns or "
                              "time (18, 19)");
    }
    if (!end_after_waypoints.empty()) {
      return invalid_argument(end_after_waypoints +
                              " (a takeoff, landing or return to launch) comes between waypoints: the legs it flies "
                              "are not in the file; they may come only before the first waypoint or after the last");
    }
    Result<long long> frame_read = item_frame(item, where);
    if (!frame_read.ok()) return frame_read.status();
    const long long frame = *frame_read;
    VISVOL_RETURN_IF_ERROR(check_params(item, where));
    nlohmann::json at_home;  // a takeoff from where the aircraft is: at the planned home
    if (takeoff_home) {
      at_home = item["params"];
      at_home[4] = takeoff_home->y();
      at_home[5] = takeoff_home->x();
    }
    const nlohmann::json& params = takeoff_home ? at_home : item["params"];
    double v[3] = {0, 0, 0};
    for (std::size_t k = 0; k < 3; ++k) {
      const nlohmann::json& p = params[4 + k];
      if (!p.is_number() || !std::isfinite(p.get<double>())) {
        return invalid_argument(where + "params[" + std::to_string(4 + k) + "] (" + kPositionNames[k] + ") " +
                                json_brief(p) + " is not a finite number");
      }
      v[k] = p.get<double>();
    }
    const double lat = v[0], lon = v[1];
    VISVOL_RETURN_IF_ERROR(check_wgs84(lat, lon, where));
    double altitude_m = v[2];
    if (frame == mavlink::kFrameGlobalRelativeAlt || frame == mavlink::kFrameGlobalRelativeAltInt) {
      if (!home) {
        Vec3 read;
        VISVOL_RETURN_IF_ERROR(read_home(mission,
                                         where + "frame " + std::to_string(frame) + " (" +
                                             frame_name(static_cast<int>(frame)) +
                                             ", above home) needs the home altitude: ",
                                         read));
        home = read;
      }
      altitude_m += home->z();
    } else if (frame != mavlink::kFrameGlobal && frame != mavlink::kFrameGlobalInt) {
      return invalid_argument(where + "frame " + std::to_string(frame) + " (" +
                              frame_name(frame >= 0 && frame < 64 ? static_cast<int>(frame) : -1) +
                              ") is not supported; visvol reads waypoints in frame 0 (MAV_FRAME_GLOBAL, above mean "
                              "sea level) or 3 (MAV_FRAME_GLOBAL_RELATIVE_ALT, above the planned home)");
    }
    if (takeoff_point) {
      out.points.push_back({lon, lat, altitude_m});
      out.hold_s.push_back(0.0);
      takeoff_where = where;
      continue;
    }
    waypoint_read = true;
    // the first waypoint: a takeoff on its spot is the mission's end, not a leg
    if (!takeoff_where.empty()) {
      const double d = apart_m(out.points.back(), Vec3(lon, lat, 0));
      if (d <= kEndOnTheSpotM) {
        out.points.pop_back();
        out.hold_s.pop_back();
      } else {
        out.notes.push_back(takeoff_where.substr(file.size(), takeoff_where.size() - file.size() - 2) + ", a takeoff " +
                            shown(d, 0) +
                            " m from the first waypoint: the leg from its point, at its altitude, is checked as "
                            "the path's first; the climb from the ground is not");
      }
      takeoff_where.clear();
    }
    const bool loiter = command != mavlink::kCmdNavWaypoint;
    if (loiter) {
      Result<LoiterItem> l = read_loiter(command, params, where);
      if (!l.ok()) return l.status();
      l->item = where.substr(file.size(), where.size() - file.size() - 2);
      l->altitude_m = altitude_m;
      // over the waypoint before it: a circle around that waypoint, no vertex of its own
      l->over_waypoint = !out.points.empty() && out.points.back().x() == lon && out.points.back().y() == lat;
      if (!l->over_waypoint) {
        out.points.push_back({lon, lat, altitude_m});
        out.hold_s.push_back(0.0);
      }
      l->vertex = out.points.size() - 1;
      if (l->kind == LoiterKind::unlimited) unlimited_loiter = where;
      out.loiters.push_back(*l);
      continue;
    }
    // param 1: the seconds a multirotor holds there (a fixed-wing ignores it)
    Result<double> hold = loiter_param(params, 0, "hold, s", 0, 1e6, 0.0, where);
    if (!hold.ok()) return hold.status();
    // param 2: how near the autopilot must come (0: its own distance)
    Result<double> accept = loiter_param(params, 1, "acceptance radius, m", 0, 1e4, 0.0, where);
    if (!accept.ok()) return accept.status();
    if (*accept > 0) out.acceptance_radius_m = std::max(out.acceptance_radius_m.value_or(0.0), *accept);
    out.points.push_back({lon, lat, altitude_m});
    out.hold_s.push_back(*hold);
  }
  // a landing after the last waypoint: a LOITER_TO_ALT over it at its
  // altitude is the landing's approach (visvol's own plans circle there),
  // flown after the path ends; any other loiter there is flown
  if (landing_after_waypoints) {
    while (!out.loiters.empty() && out.loiters.back().over_waypoint &&
           out.loiters.back().kind == LoiterKind::to_altitude && out.loiters.back().vertex + 1 == out.points.size() &&
           out.loiters.back().altitude_m == out.points.back().z()) {
      out.approach.insert(out.approach.begin(), out.loiters.back());
      out.loiters.pop_back();
    }
  }
  if (!return_where.empty()) {
    out.notes.push_back(return_where.substr(file.size(), return_where.size() - file.size() - 2) +
                        ", a return to launch: the way home from the last waypoint is flown after the path and is "
                        "not checked here");
  }
  // a landing away from the last waypoint flies its approach after the path
  if (landing && !out.points.empty() && apart_m(*landing, out.points.back()) > kEndOnTheSpotM) {
    out.notes.push_back(landing_where.substr(file.size(), landing_where.size() - file.size() - 2) + ", a landing " +
                        shown(apart_m(*landing, out.points.back()), 0) +
                        " m from the last waypoint: its approach and touchdown are flown after the path and are "
                        "not checked here");
  }
  if (out.points.size() < 2) {
    return invalid_argument(file + std::to_string(out.points.size()) +
                            " waypoints (waypoint or loiter items) in mission.items (of " +
                            std::to_string(items.size()) + "); a path needs at least 2");
  }
  if (crs_wkt.empty()) {
    return invalid_argument(file +
                            "a .plan is in WGS84 latitude and longitude, and there is no pack CRS to convert "
                            "it to");
  }
  // altitudes above mean sea level: the DEM's heights, kept
  if (home) out.points.push_back(*home);
  Wgs84Conversion conversion;
  Result<std::vector<Vec3>> projected = from_wgs84(out.points, crs_wkt, &conversion);
  if (!projected.ok()) return projected.status().with_context(path);
  out.points = std::move(*projected);
  if (std::string note = wgs84_accuracy_note(conversion); !note.empty()) out.notes.push_back(std::move(note));
  if (home) {
    out.relative_home = out.points.back();
    out.points.pop_back();
  }
  return out;
}

}  // namespace visvol::cli::detail
