// The path files `visvol plan` writes (tools/visvol/path_write): GeoJSON
// heights above the WGS84 ellipsoid, the CSV's stated CRS and datums, the
// set written whole, and the QGroundControl .plan's structure for a
// multirotor and a fixed-wing aircraft, or no mission where it is not flyable.
#include "path_io_fixture.hpp"

namespace visvol::cli {
namespace {

using namespace path_files_test;

// ---- GeoJSON ----

TEST_F(PathIo, GeoJsonHeightsAreEllipsoidalWithTheOrthometricOnesAsProperties) {
  const PathReport r = report(preset("multirotor"));
  const nlohmann::json gj = nlohmann::json::parse(slurp(write(r) + ".geojson"));
  const nlohmann::json& feature = gj["features"][0];
  const nlohmann::json& coords = feature["geometry"]["coordinates"];
  const nlohmann::json& props = feature["properties"];
  ASSERT_EQ(coords.size(), r.vertices.size());
  ASSERT_EQ(props["vertex_height_orthometric_m"].size(), r.vertices.size());
  EXPECT_EQ(props["vertical_datum_source"], "EGM96 (DEM heights taken as EGM96 orthometric)");
  EXPECT_EQ(props["vertical_datum"], "WGS 84 ellipsoid (EPSG:4979)");
  for (std::size_t i = 0; i < r.vertices.size(); ++i) {
    const double orthometric_m = props["vertex_height_orthometric_m"][i].get<double>();
    EXPECT_DOUBLE_EQ(orthometric_m, r.vertices[i].z());
    const double undulation_m = coords[i][2].get<double>() - orthometric_m;
    EXPECT_GT(undulation_m, kSfUndulationLowM) << i;
    EXPECT_LT(undulation_m, kSfUndulationHighM) << i;
    EXPECT_NEAR(coords[i][0].get<double>(), -122.43, 0.05);
    EXPECT_NEAR(coords[i][1].get<double>(), 37.79, 0.05);
  }
}

// ---- CSV ----

TEST_F(PathIo, CsvStatesItsCrsAndDatumsThenAHeaderRowAndReadsBack) {
  const PathReport r = report(preset("multirotor"));
  const std::string csv = write(r) + ".csv";
  std::ifstream in(csv);
  std::string line, comments;
  while (std::getline(in, line) && !line.empty() && line[0] == '#') {
    EXPECT_EQ(line.find(','), std::string::npos) << "a comma splits a spreadsheet's cell: " << line;
    comments += line + "\n";
  }
  EXPECT_NE(comments.find("EPSG:32610"), std::string::npos) << comments;
  EXPECT_NE(comments.find("WGS 84 / UTM zone 10N"), std::string::npos) << comments;
  EXPECT_NE(comments.find("z_m: height above the DEM's vertical datum (orthometric"), std::string::npos) << comments;
  EXPECT_NE(comments.find("lon_deg lat_deg: WGS84"), std::string::npos) << comments;
  EXPECT_NE(comments.find("h_ellipsoidal_m: height above the WGS84 ellipsoid"), std::string::npos) << comments;
  // the header row right after the comments, then a row per vertex
  EXPECT_EQ(line, "index,x_m,y_m,z_m,lon_deg,lat_deg,h_ellipsoidal_m,fp,clearance_m");
  int rows = 0;
  while (std::getline(in, line)) {
    double x = 0, y = 0, z = 0, lon = 0, lat = 0, h = 0;
    int index = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%lf,%lf,%lf,%lf,%lf,%lf", &index, &x, &y, &z, &lon, &lat, &h), 7) << line;
    EXPECT_EQ(index, rows);
    EXPECT_GT(h - z, kSfUndulationLowM);
    EXPECT_LT(h - z, kSfUndulationHighM);
    ++rows;
  }
  EXPECT_EQ(rows, static_cast<int>(r.vertices.size()));
  Result<PathFile> back = read_path_file(csv);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->format, PathFormat::plan_csv);
  expect_same_points(back->points, r.vertices, 0.001);
}

TEST_F(PathIo, WithoutACrsOnlyTheCsvIsWrittenInThePacksCoordinates) {
  PathReport r = report(preset("multirotor"));
  r.crs_wkt.clear();
  std::vector<std::string> written;
  const Status s = write_path_outputs(dir_ + "/bare", r, written);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("GeoJSON, KML and .plan not written"), std::string::npos) << s.message();
  ASSERT_EQ(written, std::vector<std::string>{dir_ + "/bare.csv"});
  const std::string csv = slurp(dir_ + "/bare.csv");
  EXPECT_NE(csv.find("\nindex,x_m,y_m,z_m,fp,clearance_m\n"), std::string::npos) << csv;
}

TEST_F(PathIo, NoFileOfAnEarlierPlanIsLeftBesideAPartSet) {
  // an earlier plan's whole set, then one that can write only its CSV: the
  // earlier KML, .plan and GeoJSON (another route) are removed, and said so
  const std::string base = dir_ + "/again";
  std::vector<std::string> written;
  ASSERT_TRUE(write_path_outputs(base, report(preset("multirotor")), written).ok());
  ASSERT_EQ(written.size(), 4u);
  PathReport bare = report(preset("multirotor"));
  bare.crs_wkt.clear();
  written.clear();
  const Status s = write_path_outputs(base, bare, written);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("(the earlier " + base + ".kml, " + base + ".plan, " + base +
                             ".geojson removed: another plan's)"),
            std::string::npos)
      << s.message();
  for (const char* gone : {".kml", ".plan", ".geojson"}) EXPECT_NE(access((base + gone).c_str(), F_OK), 0) << gone;
  EXPECT_EQ(access((base + ".csv").c_str(), F_OK), 0);
}

TEST_F(PathIo, OnlyTheFilesOfTheSetNotWrittenGoAndNeverALink) {
  // the home's ground above the first vertex: every file but the .plan is
  // written, and the earlier .plan alone is removed
  const std::string base = dir_ + "/ground";
  std::vector<std::string> written;
  ASSERT_TRUE(write_path_outputs(base, report(preset("multirotor")), written).ok());
  PathReport low = report(preset("multirotor"));
  low.home_ground_m = 300;
  written.clear();
  Status s = write_path_outputs(base, low, written);
  EXPECT_NE(s.message().find("(the earlier " + base + ".plan removed: another plan's)"), std::string::npos)
      << s.message();
  EXPECT_NE(access((base + ".plan").c_str(), F_OK), 0);
  for (const char* kept : {".csv", ".kml", ".geojson"}) EXPECT_EQ(access((base + kept).c_str(), F_OK), 0) << kept;
  // a link where a file of the set would be is never removed (nor what it names)
  const std::string victim = dir_ + "/victim.txt";
  std::ofstream(victim) << "keep\n";
  ASSERT_EQ(::symlink(victim.c_str(), (base + ".plan").c_str()), 0);
  written.clear();
  s = write_path_outputs(base, low, written);
  EXPECT_EQ(s.message().find("removed"), std::string::npos) << s.message();
  struct stat st {};
  EXPECT_EQ(::lstat((base + ".plan").c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode));
  EXPECT_EQ(slurp(victim), "keep\n");
}

// A path that breaks the envelope (29 m under the ground here) is written
// for analysis, marked unmet in every file, and gets no mission for the
// autopilot; one that only misses an observer is flyable and gets its .plan.
TEST_F(PathIo, OnlyAFlyablePathGetsAMissionAndEveryFileSaysWhatIsUnmet) {
  const std::string base = dir_ + "/unmet";
  std::vector<std::string> written;
  ASSERT_TRUE(write_path_outputs(base, report(preset("multirotor")), written).ok());
  EXPECT_NE(slurp(base + ".csv").find("# requirements: all met\n"), std::string::npos);
  PathReport under = report(preset("multirotor"));
  under.requirements_met = false;
  under.flyable = false;
  under.unmet = {"clearance 30.0 m: worst -29.0 m, holds on 0.964 of the length"};
  written.clear();
  const Status s = write_path_outputs(base, under, written);
  EXPECT_EQ(s.code(), Errc::state);
  EXPECT_NE(s.message().find(".plan not written: the path breaks the vehicle's envelope"), std::string::npos)
      << s.message();
  EXPECT_NE(s.message().find("(the earlier " + base + ".plan removed: another plan's)"), std::string::npos)
      << s.message();
  EXPECT_FALSE(exists(base + ".plan"));
  EXPECT_EQ(written.size(), 3u);
  EXPECT_NE(slurp(base + ".csv").find("# requirements: NOT MET\n#   unmet: clearance 30.0 m: worst -29.0 m; holds"),
            std::string::npos)
      << "a comment is one spreadsheet cell: no comma";
  const std::string kml = slurp(base + ".kml");
  EXPECT_NE(kml.find("<name>NOT MET: F_c"), std::string::npos) << kml;
  EXPECT_NE(kml.find("Unmet: clearance 30.0 m: worst -29.0 m"), std::string::npos) << kml;
  EXPECT_NE(slurp(base + ".geojson").find("\"requirements_met\": false"), std::string::npos);

  PathReport seen = report(preset("multirotor"));
  seen.requirements_met = false;
  seen.unmet = {"hidden-from (550500, 4182100, 5): 0.82 of the length <of 1>"};
  written.clear();
  ASSERT_TRUE(write_path_outputs(base, seen, written).ok());
  EXPECT_TRUE(exists(base + ".plan"));
  EXPECT_NE(slurp(base + ".kml").find("0.82 of the length &lt;of 1&gt;"), std::string::npos);
}

// A fixed-wing's landing circles over the last vertex before it lands: a
// circle that comes under the clearance (one came 32 m under the ground, of a
// path that met everything) gets no mission; the path's files are written.
TEST_F(PathIo, NoMissionWhoseLandingCircleComesUnderTheClearance) {
  PathReport r = report(preset("fixed-wing"));
  r.landing_loiter_clearance_m = -32.0;
  std::vector<std::string> written;
  const Status s = write_path_outputs(dir_ + "/circle", r, written);
  EXPECT_EQ(s.code(), Errc::state);
  EXPECT_NE(s.message().find(".plan not written: the landing's loiter circle (80 m around the last vertex at 230.0 m) "
                             "comes to -32.0 m over the ground, under the 30.0 m clearance"),
            std::string::npos)
      << s.message();
  EXPECT_FALSE(exists(dir_ + "/circle.plan"));
  EXPECT_EQ(written.size(), 3u);
  r.landing_loiter_clearance_m = -std::numeric_limits<double>::infinity();
  written.clear();
  EXPECT_NE(write_path_outputs(dir_ + "/off", r, written).message().find("leaves the terrain the pack knows"),
            std::string::npos);
  r.landing_loiter_clearance_m = 30.5;  // over the clearance: the mission stands
  written.clear();
  EXPECT_TRUE(write_path_outputs(dir_ + "/fine", r, written).ok());
  EXPECT_TRUE(exists(dir_ + "/fine.plan"));
}

// ---- .plan ----

TEST_F(PathIo, MultirotorPlanTakesOffAtHomeFliesTheWaypointsAndLandsAtTheEnd) {
  const PathReport r = report(preset("multirotor"));
  const nlohmann::json plan = nlohmann::json::parse(slurp(write(r) + ".plan"));
  Result<std::vector<Vec3>> geo = to_wgs84(r.vertices, wkt_);
  ASSERT_TRUE(geo.ok());
  EXPECT_EQ(plan["fileType"], "Plan");
  EXPECT_EQ(plan["version"], 1);
  EXPECT_EQ(plan["groundStation"], "QGroundControl");
  EXPECT_TRUE(plan["geoFence"].is_object());
  EXPECT_TRUE(plan["rallyPoints"].is_object());
  const nlohmann::json& m = plan["mission"];
  EXPECT_EQ(m["version"], 2);
  EXPECT_EQ(m["firmwareType"], mavlink::kAutopilotPx4);
  EXPECT_EQ(m["vehicleType"], mavlink::kTypeQuadrotor);
  EXPECT_DOUBLE_EQ(m["cruiseSpeed"].get<double>(), 8.0);  // the multirotor preset's speed
  EXPECT_DOUBLE_EQ(m["hoverSpeed"].get<double>(), 8.0);
  // home: on the ground below the start
  ASSERT_EQ(m["plannedHomePosition"].size(), 3u);
  EXPECT_NEAR(m["plannedHomePosition"][0].get<double>(), (*geo)[0].y(), 1e-9);
  EXPECT_NEAR(m["plannedHomePosition"][1].get<double>(), (*geo)[0].x(), 1e-9);
  EXPECT_DOUBLE_EQ(m["plannedHomePosition"][2].get<double>(), 230.0);
  // takeoff, the waypoints in order, land
  const std::size_t n = r.vertices.size();
  ASSERT_EQ(m["items"].size(), n + 2);
  EXPECT_EQ(item(plan, 0)["command"], mavlink::kCmdNavTakeoff);
  expect_position(item(plan, 0), (*geo)[0], r.vertices[0].z());
  for (std::size_t i = 0; i < n; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(item(plan, i + 1)["command"], mavlink::kCmdNavWaypoint);
    expect_position(item(plan, i + 1), (*geo)[i], r.vertices[i].z());
    EXPECT_DOUBLE_EQ(item(plan, i + 1)["params"][1].get<double>(), 0.0);  // acceptance: the autopilot's own
  }
  EXPECT_EQ(item(plan, n + 1)["command"], mavlink::kCmdNavLand);
  expect_position(item(plan, n + 1), (*geo)[n - 1], 215.0);
  for (std::size_t i = 0; i < n + 2; ++i) EXPECT_EQ(item(plan, i)["doJumpId"], static_cast<int>(i) + 1);
}

TEST_F(PathIo, FixedWingPlanLoitersOverTheEndThenLands) {
  rt::VehicleEnvelope v = preset("fixed-wing");
  v.speed_m_per_s = 23.5;      // the envelope's, not a constant
  v.acceptance_radius_m = 45;  // the vehicle's, written as each waypoint's param 2
  v.min_turn_radius_m = 95.0;
  PathReport r = report(v);
  r.vehicle.autopilot = rt::Autopilot::ardupilot;
  const nlohmann::json plan = nlohmann::json::parse(slurp(write(r) + ".plan"));
  Result<std::vector<Vec3>> geo = to_wgs84(r.vertices, wkt_);
  ASSERT_TRUE(geo.ok());
  const nlohmann::json& m = plan["mission"];
  EXPECT_EQ(m["firmwareType"], mavlink::kAutopilotArduPilotMega);
  EXPECT_EQ(m["vehicleType"], mavlink::kTypeFixedWing);
  EXPECT_DOUBLE_EQ(m["cruiseSpeed"].get<double>(), 23.5);
  const std::size_t n = r.vertices.size();
  ASSERT_EQ(m["items"].size(), n + 4);
  EXPECT_EQ(item(plan, 0)["command"], mavlink::kCmdNavTakeoff);
  EXPECT_DOUBLE_EQ(item(plan, 0)["params"][0].get<double>(), v.max_climb_deg);  // takeoff pitch
  expect_position(item(plan, 0), (*geo)[0], r.vertices[0].z());
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(item(plan, i + 1)["command"], mavlink::kCmdNavWaypoint);
    // param 2: the acceptance radius the check assumed (the heights early)
    EXPECT_DOUBLE_EQ(item(plan, i + 1)["params"][1].get<double>(), v.acceptance_radius_m);
  }
  EXPECT_EQ(item(plan, n + 1)["command"], mavlink::kCmdDoLandStart);
  EXPECT_EQ(item(plan, n + 2)["command"], mavlink::kCmdNavLoiterToAlt);
  expect_position(item(plan, n + 2), (*geo)[n - 1], r.vertices[n - 1].z());
  EXPECT_DOUBLE_EQ(item(plan, n + 2)["params"][1].get<double>(), 95.0);  // loiter radius: the turn radius
  EXPECT_EQ(item(plan, n + 3)["command"], mavlink::kCmdNavLand);
  expect_position(item(plan, n + 3), (*geo)[n - 1], 215.0);
}

// ---- the report ----

TEST_F(PathIo, AReportThatDoesNotHoldTogetherWritesNothing) {
  PathReport unset = report(preset("multirotor"));
  unset.home_ground_m = std::nan("");
  PathReport short_info = report(preset("multirotor"));
  short_info.per_vertex.pop_back();
  PathReport slow = report(preset("multirotor"));
  slow.vehicle.speed_m_per_s = 0;
  const struct {
    const PathReport* report;
    const char* message;
  } cases[] = {{&unset, "home_ground_m is not set"},
               {&short_info, "3 per-vertex values for 4 vertices"},
               {&slow, "vehicle multirotor: speed 0.000000 m/s is not above 0"}};
  for (const auto& c : cases) {
    std::vector<std::string> written;
    const Status s = write_path_outputs(dir_ + "/bad", *c.report, written);
    EXPECT_EQ(s.code(), Errc::invalid_argument);
    EXPECT_NE(s.message().find(c.message), std::string::npos) << s.message();
    EXPECT_TRUE(written.empty());
    EXPECT_FALSE(exists(dir_ + "/bad.csv"));
  }
}

// A path starting below its ground would take off downwards: no .plan, the
// other files still written.
TEST_F(PathIo, APathStartingBelowTheGroundGetsNoPlan) {
  PathReport r = report(preset("multirotor"));
  r.home_ground_m = 300;
  std::vector<std::string> written;
  const Status s = write_path_outputs(dir_ + "/under", r, written);
  EXPECT_NE(s.message().find(".plan not written: home_ground_m 300.00 m is above the first vertex (250.00 m)"),
            std::string::npos)
      << s.message();
  EXPECT_EQ(written.size(), 3u);
  EXPECT_FALSE(exists(dir_ + "/under.plan"));
  EXPECT_TRUE(exists(dir_ + "/under.geojson"));
}

}  // namespace
}  // namespace visvol::cli
