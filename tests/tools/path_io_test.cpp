// The path files `visvol plan`, `render` and `check` read (tools/visvol/path_io):
// GeoJSON heights read back to the DEM's datum, other tools' files, .plan
// missions read as paths, text and CSV numbers, and bad files refused with
// messages naming the file, the item and the problem.
#include "path_io_fixture.hpp"

namespace visvol::cli {
namespace {

using namespace path_files_test;

// ---- GeoJSON ----

TEST_F(PathIo, GeoJsonReadsBackToTheSamePointsWithinACentimetre) {
  const PathReport r = report(preset("fixed-wing"));
  Result<PathFile> back = read_path_file(write(r) + ".geojson", wkt_);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->format, PathFormat::geojson);
  EXPECT_TRUE(back->has_heights);
  expect_same_points(back->points, r.vertices, 0.01);
  ASSERT_EQ(back->fp.size(), r.vertices.size());
  EXPECT_DOUBLE_EQ(back->fp[2], 0.2);
}

// RFC 7946: another tool's heights are ellipsoidal; they become the DEM's.
TEST_F(PathIo, ForeignGeoJsonHeightsAreReadAsEllipsoidal) {
  const std::string f = file_with("foreign.geojson", R"({"type":"LineString","coordinates":)"
                                                     R"([[-122.43,37.79,100.0],[-122.42,37.78,120.0]]})");
  Result<PathFile> path = read_path_file(f, wkt_);
  ASSERT_TRUE(path.ok()) << path.status().message();
  const double undulation_m = 100.0 - path->points[0].z();
  EXPECT_GT(undulation_m, kSfUndulationLowM);
  EXPECT_LT(undulation_m, kSfUndulationHighM);
  EXPECT_NEAR((120.0 - path->points[1].z()) - undulation_m, 0.0, 0.2);  // the geoid is smooth over a kilometre
}

// A GeoJSON visvol wrote before heights were ellipsoidal says so: read as it is.
TEST_F(PathIo, EarlierVisvolGeoJsonWithOrthometricHeightsIsReadAsItIs) {
  const std::string f =
      file_with("old.geojson",
                R"j({"type":"Feature","properties":{"height_reference":"the DEM's vertical datum (mean sea level)"},)j"
                R"("geometry":{"type":"LineString","coordinates":[[-122.43,37.79,100.0],[-122.42,37.78,120.0]]}})");
  Result<PathFile> path = read_path_file(f, wkt_);
  ASSERT_TRUE(path.ok()) << path.status().message();
  EXPECT_NEAR(path->points[0].z(), 100.0, 1e-9);
  EXPECT_NEAR(path->points[1].z(), 120.0, 1e-9);
}

// Nothing beside the path's LineString that could be another route, and no
// CRS but WGS84's, is left out unseen (a skeptic's files read "all met").
TEST_F(PathIo, GeoJsonWithAnotherRouteOrCrsIsRefused) {
  const std::string line = R"({"type":"Feature","properties":{"vertical_datum":"EGM96"},"geometry":)"
                           R"({"type":"LineString","coordinates":[[-122.43,37.79,100.0],[-122.42,37.78,120.0]]}})";
  auto collection = [&](const std::string& members, const std::string& extra = "") {
    return R"({"type":"FeatureCollection",)" + extra + R"("features":[)" + line + members + "]}";
  };
  const std::pair<std::string, std::string> refused[] = {
      {collection(R"(,{"type":"Feature","geometry":{"type":"MultiLineString","coordinates":)"
                  R"([[[-122.43,37.79,-20],[-122.42,37.78,-20]]]}})"),
       "a MultiLineString beside the path's LineString"},
      {collection(R"(,{"type":"feature","geometry":{"type":"LineString","coordinates":[[0,0],[1,1]]}})"),
       "features[1] (type \"feature\") is not a Feature with a geometry"},
      {collection("", R"("crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::4267"}},)"), "\"crs\""},
      {R"({"type":"Feature","crs":{"type":"name","properties":{"name":"EPSG:26710"}},"geometry":)"
       R"({"type":"LineString","coordinates":[[-122.43,37.79,100.0],[-122.42,37.78,120.0]]}})",
       "\"crs\""},
  };
  for (const auto& [text, named] : refused) {
    Result<PathFile> path = read_path_file(file_with("other.geojson", text), wkt_);
    ASSERT_FALSE(path.ok()) << text;
    EXPECT_NE(path.status().message().find(named), std::string::npos) << path.status().message();
  }
  // points beside it (waypoint markers, observers) and a CRS84 "crs" are read
  const std::string fine[] = {
      collection(R"(,{"type":"Feature","properties":null,"geometry":{"type":"Point","coordinates":[-122.4,37.7]}})"),
      collection("", R"("crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:OGC:1.3:CRS84"}},)")};
  for (const std::string& text : fine) {
    Result<PathFile> path = read_path_file(file_with("fine.geojson", text), wkt_);
    ASSERT_TRUE(path.ok()) << path.status().message();
    EXPECT_EQ(path->points.size(), 2u);
  }
}

// A GeoJSON that names its vertical datum is read by it: mean sea level
// (EGM96) as it is, the ellipsoid converted, anything else refused by name.
TEST_F(PathIo, GeoJsonVerticalDatumIsHonouredOrRefused) {
  auto with_datum = [&](const std::string& datum) {
    return file_with("datum.geojson", R"j({"type":"Feature","properties":{"vertical_datum":)j" + datum +
                                          R"(},"geometry":{"type":"LineString","coordinates":)"
                                          R"([[-122.43,37.79,100.0],[-122.42,37.78,120.0]]}})");
  };
  for (const char* msl : {R"("EGM96 geoid")", R"("mean sea level")"}) {
    Result<PathFile> path = read_path_file(with_datum(msl), wkt_);
    ASSERT_TRUE(path.ok()) << path.status().message();
    EXPECT_NEAR(path->points[0].z(), 100.0, 1e-9) << msl;
  }
  Result<PathFile> ellipsoid = read_path_file(with_datum(R"j("WGS 84 ellipsoid (EPSG:4979)")j"), wkt_);
  ASSERT_TRUE(ellipsoid.ok()) << ellipsoid.status().message();
  EXPECT_GT(100.0 - ellipsoid->points[0].z(), kSfUndulationLowM);
  for (const char* other : {R"("NAVD88")", "42"}) {
    Result<PathFile> path = read_path_file(with_datum(other), wkt_);
    ASSERT_FALSE(path.ok()) << other;
    EXPECT_NE(path.status().message().find("datum.geojson: vertical_datum"), std::string::npos)
        << path.status().message();
  }
}

// ---- .plan ----

TEST_F(PathIo, PlanReadsBackToItsWaypoints) {
  for (const char* vehicle : {"multirotor", "fixed-wing"}) {
    SCOPED_TRACE(vehicle);
    const PathReport r = report(preset(vehicle));
    Result<PathFile> back = read_path_file(write(r, vehicle) + ".plan", wkt_);
    ASSERT_TRUE(back.ok()) << back.status().message();
    EXPECT_EQ(back->format, PathFormat::qgc_plan);
    EXPECT_TRUE(back->has_heights);
    EXPECT_TRUE(back->fp.empty());
    expect_same_points(back->points, r.vertices, 0.01);
  }
}

std::string plan_text(const std::string& items, const std::string& home = "[37.79, -122.43, 10.0]") {
  return R"({"fileType":"Plan","version":1,"groundStation":"QGroundControl","mission":{"version":2,)"
         R"("firmwareType":12,"vehicleType":2,"plannedHomePosition":)" +
         home + R"(,"items":[)" + items + "]}}";
}

std::string waypoint(int frame, const std::string& lat, const std::string& lon, const std::string& alt,
                     int command = mavlink::kCmdNavWaypoint) {
  return R"({"type":"SimpleItem","autoContinue":true,"doJumpId":1,"command":)" + std::to_string(command) +
         R"(,"frame":)" + std::to_string(frame) + R"(,"params":[0,0,0,null,)" + lat + "," + lon + "," + alt + "]}";
}

// Another engineer's mission: altitudes above home get home's altitude; the
// takeoff and land items are not part of the path.
TEST_F(PathIo, PlanWaypointsAboveHomeAreLiftedByHomesAltitude) {
  const std::string f = file_with(
      "relative.plan",
      plan_text(waypoint(mavlink::kFrameGlobalRelativeAlt, "37.79", "-122.43", "40", mavlink::kCmdNavTakeoff) + "," +
                waypoint(mavlink::kFrameGlobalRelativeAlt, "37.79", "-122.43", "50") + "," +
                waypoint(mavlink::kFrameGlobal, "37.78", "-122.42", "70") + "," +
                waypoint(mavlink::kFrameGlobalRelativeAlt, "37.78", "-122.42", "0", mavlink::kCmdNavLand)));
  Result<PathFile> path = read_path_file(f, wkt_);
  ASSERT_TRUE(path.ok()) << path.status().message();
  ASSERT_EQ(path->points.size(), 2u);
  EXPECT_NEAR(path->points[0].z(), 60.0, 1e-9);  // 50 above a home at 10
  EXPECT_NEAR(path->points[1].z(), 70.0, 1e-9);  // above mean sea level
  Result<std::vector<Vec3>> lon_lat = to_wgs84(path->points, wkt_);
  ASSERT_TRUE(lon_lat.ok());
  EXPECT_NEAR((*lon_lat)[0].x(), -122.43, 1e-8);
  EXPECT_NEAR((*lon_lat)[0].y(), 37.79, 1e-8);
}

// The aircraft flies to loiters too: they are vertices (a loiter at its
// centre), so a check sees them; speed, camera, ROI and condition items move
// nothing and are left out, as are takeoff, landing and return to launch
// (the mission's ends, on the spot of the first and last waypoints).
TEST_F(PathIo, PlanLoitersAreVerticesOtherItemsAreLeftOut) {
  const std::string f = file_with(
      "mixed.plan",
      plan_text(waypoint(0, "37.790", "-122.430", "50", mavlink::kCmdNavTakeoff) + "," +
                waypoint(0, "37.790", "-122.430", "50") + "," + waypoint(0, "37.789", "-122.429", "5") + "," +
                waypoint(0, "0", "0", "0", 178) + "," +         // DO_CHANGE_SPEED
                waypoint(0, "0", "0", "0", 2000) + "," +        // IMAGE_START_CAPTURE
                waypoint(0, "0", "0", "0", 206) + "," +         // DO_SET_CAM_TRIGG_DIST
                waypoint(0, "37.7", "-122.4", "0", 80) + "," +  // NAV_ROI
                waypoint(0, "0", "0", "0", 112) + "," +         // CONDITION_DELAY
                waypoint(0, "37.788", "-122.428", "60", 19) + "," + waypoint(0, "37.786", "-122.426", "62", 18) + "," +
                waypoint(0, "37.785", "-122.425", "63", mavlink::kCmdNavLoiterToAlt) + "," +
                waypoint(0, "37.784", "-122.424", "64", 17) + "," +  // the last: it circles there for ever
                waypoint(0, "37.784", "-122.424", "0", mavlink::kCmdNavLand) + "," +
                waypoint(0, "37.784", "-122.424", "0", mavlink::kCmdNavVtolLand) + "," +
                waypoint(0, "0", "0", "0", mavlink::kCmdNavReturnToLaunch)));
  Result<PathFile> path = read_path_file(f, wkt_);
  ASSERT_TRUE(path.ok()) << path.status().message();
  ASSERT_EQ(path->points.size(), 6u);
  EXPECT_NEAR(path->points[1].z(), 5.0, 1e-9);  // low: a check must see it
  EXPECT_NEAR(path->points[5].z(), 64.0, 1e-9);
  // the loiters, each at its own vertex (a check flies their circles)
  ASSERT_EQ(path->loiters.size(), 4u);
  const LoiterKind kinds[] = {LoiterKind::time, LoiterKind::turns, LoiterKind::to_altitude, LoiterKind::unlimited};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(path->loiters[k].kind, kinds[k]);
    EXPECT_EQ(path->loiters[k].vertex, k + 2);
    EXPECT_FALSE(path->loiters[k].over_waypoint);
  }
  EXPECT_EQ(path->loiters[3].item, "mission.items[11] (doJumpId 1)");
}

// A takeoff away from the first waypoint (QGroundControl puts a
// multirotor's at home): its point, at its altitude, starts the path, so the
// leg to the first waypoint is checked (a 3.4 km climb-out 25 m over the
// ground read as met, left out); on the waypoint's spot it is dropped. A
// landing away from the last waypoint is said in a note: its approach is
// flown after the path.
TEST_F(PathIo, PlanTakeoffAwayStartsThePathALandingAwayIsNoted) {
  const std::string wp1 = waypoint(0, "37.79", "-122.43", "50"), wp2 = waypoint(0, "37.78", "-122.42", "60");
  Result<PathFile> away = read_path_file(
      file_with("away.plan", plan_text(waypoint(3, "37.76", "-122.43", "30", mavlink::kCmdNavTakeoff) + "," + wp1 +
                                       "," + wp2 + "," + waypoint(0, "37.78", "-122.40", "0", mavlink::kCmdNavLand))),
      wkt_);
  ASSERT_TRUE(away.ok()) << away.status().message();
  ASSERT_EQ(away->points.size(), 3u);
  EXPECT_NEAR(away->points[0].z(), 40.0, 1e-9);  // 30 m above a home at 10
  ASSERT_EQ(away->notes.size(), 2u);
  EXPECT_NE(away->notes[0].find("mission.items[0] (doJumpId 1), a takeoff 3340 m from the first waypoint"),
            std::string::npos)
      << away->notes[0];
  EXPECT_NE(away->notes[1].find("mission.items[3] (doJumpId 1), a landing 1760 m from the last waypoint"),
            std::string::npos)
      << away->notes[1];
  // a takeoff "where the aircraft is" (0, 0: Mission Planner's way) is at
  // the planned home, as one at home's position; a return to launch is noted
  Result<PathFile> from_home = read_path_file(
      file_with("home.plan", plan_text(waypoint(3, "0", "0", "30", mavlink::kCmdNavTakeoff) + "," + wp1 + "," + wp2 +
                                           "," + waypoint(0, "0", "0", "0", mavlink::kCmdNavReturnToLaunch),
                                       "[37.76, -122.43, 10.0]")),
      wkt_);
  ASSERT_TRUE(from_home.ok()) << from_home.status().message();
  ASSERT_EQ(from_home->points.size(), 3u);
  EXPECT_NEAR(from_home->points[0].z(), 40.0, 1e-9);
  ASSERT_EQ(from_home->notes.size(), 2u);
  EXPECT_NE(from_home->notes[0].find("a takeoff 3340 m from the first waypoint"), std::string::npos);
  EXPECT_NE(from_home->notes[1].find("a return to launch: the way home"), std::string::npos) << from_home->notes[1];
  // a loiter first: its vertex counts the takeoff's point where it is kept,
  // and not where it is dropped; a hold for every point
  const std::string loiter1 = waypoint(0, "37.79", "-122.43", "50", mavlink::kCmdNavLoiterTurns);
  for (const auto& [takeoff_lat, kept] : {std::pair{"37.76", true}, std::pair{"37.79001", false}}) {
    Result<PathFile> l = read_path_file(
        file_with("loiter_first.plan", plan_text(waypoint(0, takeoff_lat, "-122.43", "50", mavlink::kCmdNavTakeoff) +
                                                 "," + loiter1 + "," + wp2)),
        wkt_);
    ASSERT_TRUE(l.ok()) << l.status().message();
    ASSERT_EQ(l->loiters.size(), 1u);
    EXPECT_EQ(l->loiters[0].vertex, kept ? 1u : 0u) << takeoff_lat;
    EXPECT_EQ(l->points.size(), kept ? 3u : 2u) << takeoff_lat;
    EXPECT_EQ(l->hold_s.size(), l->points.size()) << takeoff_lat;
  }
  // on the spots: no leg, no note (visvol's own plans)
  Result<PathFile> spot = read_path_file(
      file_with("spot.plan", plan_text(waypoint(0, "37.79001", "-122.43", "50", mavlink::kCmdNavTakeoff) + "," + wp1 +
                                       "," + wp2 + "," + waypoint(0, "37.78", "-122.42", "0", mavlink::kCmdNavLand))),
      wkt_);
  ASSERT_TRUE(spot.ok()) << spot.status().message();
  EXPECT_EQ(spot->points.size(), 2u);
  EXPECT_TRUE(spot->notes.empty());
}

// What a loiter item says of its circle, as MAVLink places it: turns or
// seconds in param 1, the radius in param 3 (LOITER_TO_ALT: param 2),
// negative counter-clockwise; one over the waypoint before it has no vertex
// of its own; bad values are refused by item and parameter.
TEST_F(PathIo, PlanLoitersAreReadWithTheirCircles) {
  auto item = [](int command, const std::string& params) {
    return R"({"type":"SimpleItem","autoContinue":true,"doJumpId":7,"command":)" + std::to_string(command) +
           R"(,"frame":0,"params":[)" + params + "]}";
  };
  const std::string a = waypoint(0, "37.790", "-122.430", "50"), b = waypoint(0, "37.789", "-122.429", "60");
  const std::string f = file_with("loiters.plan", plan_text(a + "," + item(18, "3,0,-120,0,37.790,-122.430,80") + "," +
                                                            b + "," + item(19, "45,0,90,0,37.788,-122.428,70") + "," +
                                                            item(31, "0,150,0,0,37.787,-122.427,90")));
  Result<PathFile> path = read_path_file(f, wkt_);
  ASSERT_TRUE(path.ok()) << path.status().message();
  ASSERT_EQ(path->points.size(), 4u);  // a, b and the two loiters' centres
  ASSERT_EQ(path->loiters.size(), 3u);
  const LoiterItem& over = path->loiters[0];
  EXPECT_TRUE(over.over_waypoint);
  EXPECT_EQ(over.vertex, 0u);
  EXPECT_EQ(over.kind, LoiterKind::turns);
  EXPECT_EQ(over.amount, 3.0);
  EXPECT_EQ(over.radius_m, -120.0);
  EXPECT_EQ(over.altitude_m, 80.0);
  EXPECT_EQ(path->loiters[1].kind, LoiterKind::time);
  EXPECT_EQ(path->loiters[1].amount, 45.0);
  EXPECT_EQ(path->loiters[1].radius_m, 90.0);
  EXPECT_EQ(path->loiters[1].vertex, 2u);
  EXPECT_EQ(path->loiters[2].kind, LoiterKind::to_altitude);
  EXPECT_EQ(path->loiters[2].radius_m, 150.0);
  // over the last waypoint before a landing: at its altitude, the landing's
  // approach (not flown); at another, or before a return to launch, flown
  const std::string land = waypoint(0, "37.789", "-122.429", "0", mavlink::kCmdNavLand);
  const std::string rtl = waypoint(0, "0", "0", "0", mavlink::kCmdNavReturnToLaunch);
  const std::string circle_at_b = item(31, "0,80,0,0,37.789,-122.429,60");
  const std::string circle_below_b = item(31, "0,80,0,0,37.789,-122.429,20");
  const std::string turns_at_b = item(18, "50,0,3000,0,37.789,-122.429,60");
  const struct {
    std::string items;
    std::size_t loiters;
  } ends[] = {{a + "," + b + "," + circle_at_b + "," + land, 0},
              {a + "," + b + "," + circle_below_b + "," + land, 1},
              {a + "," + b + "," + circle_at_b + "," + rtl, 1},
              {a + "," + b + "," + turns_at_b + "," + land, 1}};  // only LOITER_TO_ALT is an approach
  for (const auto& e : ends) {
    Result<PathFile> read = read_path_file(file_with("end.plan", plan_text(e.items)), wkt_);
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_EQ(read->loiters.size(), e.loiters) << e.items;
  }
  for (const std::string& bad : {item(18, "-1,0,50,0,37.789,-122.429,60"), item(19, "2e6,0,50,0,37.789,-122.429,60"),
                                 item(18, R"(2,0,"x",0,37.789,-122.429,60)"), item(17, "0,0,1e6,0,37.789,-122.429,60"),
                                 item(18, "null,0,50,0,37.789,-122.429,60")}) {
    Result<PathFile> refused = read_path_file(file_with("bad.plan", plan_text(a + "," + bad)), wkt_);
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_NE(refused.status().message().find("bad.plan: mission.items[1] (doJumpId 7): params["), std::string::npos)
        << refused.status().message();
  }
}

// A first line with a number in it is a point, mistyped or not: never taken
// for a header and dropped. A header without numbers and a byte order mark
// are fine.
TEST_F(PathIo, TextFirstLineIsAHeaderOnlyWithoutNumbers) {
  Result<PathFile> typo = read_path_file(file_with("typo.txt", "550300 4181900 2O\n550500 4182100 200\n"), wkt_);
  ASSERT_FALSE(typo.ok());
  EXPECT_NE(typo.status().message().find("typo.txt: line 1: '550300 4181900 2O' is not numbers x y [z]"),
            std::string::npos)
      << typo.status().message();
  const std::string bom = "\xEF\xBB\xBF";
  for (const std::string& text :
       {std::string("x y z\n1 2 3\n4 5 6\n"), bom + "1 2 3\n4 5 6\n", bom + "east north up\n1 2 3\n4 5 6\n"}) {
    Result<PathFile> path = read_path_file(file_with("ok.txt", text), wkt_);
    ASSERT_TRUE(path.ok()) << path.status().message();
    ASSERT_EQ(path->points.size(), 2u);
    EXPECT_EQ(path->points[0], Vec3(1, 2, 3));
  }
  const PathReport r = report(preset("fixed-wing"));  // a visvol GeoJSON saved by an editor with a byte order mark
  Result<PathFile> geojson = read_path_file(file_with("bom.geojson", bom + slurp(write(r) + ".geojson")), wkt_);
  ASSERT_TRUE(geojson.ok()) << geojson.status().message();
  EXPECT_EQ(geojson->format, PathFormat::geojson);
}

// Numbers in text and CSV paths are decimal: strtod's hexadecimal, "inf"
// and "nan" are typing mistakes there, and a header with digits is pointed
// at the '#' that makes it a comment.
TEST_F(PathIo, TextAndCsvNumbersAreDecimalOnly) {
  for (const char* bad : {"0x1p20", "0x10", "inf", "nan", "1e400", "1.2.3", "+", "1e", ".", "1,5e"}) {
    const std::string text = std::string(bad) + " 4181900 200\n550500 4182100 200\n";
    Result<PathFile> path = read_path_file(file_with("bad.txt", text), wkt_);
    ASSERT_FALSE(path.ok()) << bad;
    EXPECT_NE(path.status().message().find("bad.txt: line 1:"), std::string::npos) << path.status().message();
    // a line that begins with a number is a mistyped point, not a header
    const bool header_like = std::isalpha(static_cast<unsigned char>(bad[0])) != 0;
    EXPECT_EQ(path.status().message().find("'#'") != std::string::npos, header_like) << path.status().message();
    const std::string csv = "i,x_m,y_m,z_m\n0," + std::string(bad) + ",4181900,200\n1,550500,4182100,200\n";
    Result<PathFile> plan_csv = read_path_file(file_with("bad.csv", csv), wkt_);
    ASSERT_FALSE(plan_csv.ok()) << bad;
    EXPECT_NE(plan_csv.status().message().find("bad.csv: line 2:"), std::string::npos) << plan_csv.status().message();
  }
  for (const char* good : {"550300", "+550300", "550300.", "550300.25", "5.503e5", "5503E+2", ".5e6"}) {
    const std::string text = std::string(good) + " 4181900 200\n550500 4182100 200\n";
    Result<PathFile> path = read_path_file(file_with("good.txt", text), wkt_);
    ASSERT_TRUE(path.ok()) << good << ": " << path.status().message();
    EXPECT_GT(path->points[0].x(), 5e4);
  }
  Result<PathFile> header = read_path_file(file_with("hdr.txt", "E_32633 N Z\n1 2 3\n4 5 6\n"), wkt_);
  ASSERT_FALSE(header.ok());
  EXPECT_NE(header.status().message().find("start it with '#'"), std::string::npos) << header.status().message();
  Result<PathFile> commented = read_path_file(file_with("hdr.txt", "# E_32633 N Z\n1 2 3\n4 5 6\n"), wkt_);
  EXPECT_TRUE(commented.ok()) << commented.status().message();
  // past the first line, no hint: a bad point is not a header
  Result<PathFile> later = read_path_file(file_with("late.txt", "1 2 3\nE_32633 N Z\n4 5 6\n"), wkt_);
  ASSERT_FALSE(later.ok());
  EXPECT_EQ(later.status().message().find("'#'"), std::string::npos) << later.status().message();
  // a column named twice: the reader took the last (a path at 500 m read for
  // one at 100 m); which one is the path is not its to guess
  Result<PathFile> twice = read_path_file(
      file_with("twice.csv", "i,x_m,y_m,z_m,z_m\n0,550300,4181900,100,500\n1,550500,4182100,100,500\n"), wkt_);
  ASSERT_FALSE(twice.ok());
  EXPECT_NE(twice.status().message().find("twice.csv: line 1: the header names z_m twice (columns 4 and 5)"),
            std::string::npos)
      << twice.status().message();
}

// A takeoff, landing or return between waypoints flies legs the file does
// not hold: refused, naming the item; at the mission's ends they are fine.
TEST_F(PathIo, PlanEndItemsBetweenWaypointsAreRefused) {
  const std::string a = waypoint(0, "37.790", "-122.430", "50"), b = waypoint(0, "37.789", "-122.429", "60");
  const std::string c = waypoint(0, "37.788", "-122.428", "70");
  const std::string rtl = waypoint(0, "0", "0", "0", mavlink::kCmdNavReturnToLaunch);
  const std::string land = waypoint(0, "37.788", "-122.428", "0", mavlink::kCmdNavLand);
  const std::string takeoff = waypoint(0, "37.790", "-122.430", "50", mavlink::kCmdNavTakeoff);
  for (const std::string& items :
       {a + "," + b + "," + rtl + "," + c, a + "," + land + "," + b, takeoff + "," + a + "," + takeoff + "," + b}) {
    Result<PathFile> path = read_path_file(file_with("mid.plan", plan_text(items)), wkt_);
    ASSERT_FALSE(path.ok()) << items;
    EXPECT_NE(path.status().message().find("comes between waypoints"), std::string::npos) << path.status().message();
    EXPECT_NE(path.status().message().find("mid.plan: mission.items["), std::string::npos) << path.status().message();
  }
  Result<PathFile> ends = read_path_file(
      file_with("ends.plan", plan_text(takeoff + "," + a + "," + b + "," + c + "," + land + "," + rtl)), wkt_);
  ASSERT_TRUE(ends.ok()) << ends.status().message();
  EXPECT_EQ(ends->points.size(), 3u);
}

// A path that goes nowhere would pass every limit: refused in every format.
TEST_F(PathIo, APathWhosePointsAreAllTheSameIsRefused) {
  Result<PathFile> same = read_path_file(file_with("same.txt", "1 2 3\n1 2 3\n1 2 3.001\n"), wkt_);
  ASSERT_FALSE(same.ok());
  EXPECT_NE(same.status().message().find("same.txt: all 3 points are the same position"), std::string::npos)
      << same.status().message();
  EXPECT_TRUE(read_path_file(file_with("climb.txt", "1 2 3\n1 2 13\n"), wkt_).ok());  // straight up is a path
  const std::string wp = waypoint(mavlink::kFrameGlobal, "37.79", "-122.43", "50");
  Result<PathFile> plan = read_path_file(file_with("same.plan", plan_text(wp + "," + wp)), wkt_);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.status().message().find("all 2 points are the same position"), std::string::npos)
      << plan.status().message();
}

TEST_F(PathIo, BadPlansAreRefusedNamingTheFileTheItemAndTheProblem) {
  const std::string wp = waypoint(mavlink::kFrameGlobal, "37.79", "-122.43", "50");
  const struct {
    const char* name;
    std::string text;
    const char* message;
  } cases[] = {
      {"terrain.plan", plan_text(wp + "," + waypoint(mavlink::kFrameGlobalTerrainAlt, "37.78", "-122.42", "60")),
       "terrain.plan: mission.items[1] (doJumpId 1): frame 10 (MAV_FRAME_GLOBAL_TERRAIN_ALT, above the terrain) is "
       "not supported"},
      {"local.plan", plan_text(wp + "," + waypoint(1, "37.78", "-122.42", "60")),
       "local.plan: mission.items[1] (doJumpId 1): frame 1 (MAV_FRAME_LOCAL_NED) is not supported"},
      {"no_items.plan",
       R"({"fileType":"Plan","version":1,"mission":{"version":2,"plannedHomePosition":[37.79,-122.43,10]}})",
       "no_items.plan: mission.items is missing or not an array"},
      {"no_mission.plan", R"({"fileType":"Plan","version":1})", "no_mission.plan: no mission object"},
      {"latitude.plan", plan_text(wp + "," + waypoint(0, R"("north")", "-122.42", "60")),
       "latitude.plan: mission.items[1] (doJumpId 1): params[4] (latitude) \"north\" is not a finite number"},
      {"altitude.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "null")),
       "altitude.plan: mission.items[1] (doJumpId 1): params[6] (altitude) null is not a finite number"},
      {"command.plan", plan_text(wp + R"(,{"type":"SimpleItem","command":"waypoint","frame":0,"params":[]})"),
       "command.plan: mission.items[1]: command \"waypoint\" is not an integer"},
      {"params.plan", plan_text(wp + R"(,{"type":"SimpleItem","command":16,"frame":0,"params":[1,2,3]})"),
       "params.plan: mission.items[1]: params is missing or not an array of 7"},
      {"one.plan", plan_text(wp),
       "one.plan: 1 waypoints (waypoint or loiter items) in mission.items (of 1); a path needs at least 2"},
      // what is flown and not in the file: a spline's curve (judged as straight
      // legs, it read as met 157 m off them), waypoints after the mission has
      // ended or while it circles
      {"spline.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 82) + "," + wp),
       "spline.plan: mission.items[1] (doJumpId 1): command 82 (a spline waypoint): the autopilot flies a curve"},
      {"land_first.plan",
       plan_text(waypoint(0, "0", "0", "0", mavlink::kCmdNavReturnToLaunch) + "," + wp + "," +
                 waypoint(0, "37.78", "-122.42", "60")),
       "land_first.plan: mission.items[0] (doJumpId 1): command 20 (a landing or return to launch) comes before the "
       "first waypoint: the mission ends there"},
      // a landing's or takeoff's numbers are read as a waypoint's (a string
      // latitude, 1e308 m, frame 99 were left unread)
      {"land_lat.plan", plan_text(wp + "," + wp + "," + waypoint(0, R"("37.78")", "-122.42", "0", 21)),
       "land_lat.plan: mission.items[2] (doJumpId 1): params[4] (latitude) \"37.78\" is not a number"},
      {"land_alt.plan", plan_text(wp + "," + wp + "," + waypoint(0, "37.78", "-122.42", "1e308", 21)),
       "land_alt.plan: mission.items[2] (doJumpId 1): params[6] (altitude)"},
      {"land_frame.plan", plan_text(wp + "," + wp + "," + waypoint(99, "37.78", "-122.42", "0", 21)),
       "land_frame.plan: mission.items[2] (doJumpId 1): frame 99"},
      {"takeoff_params.plan",
       plan_text(R"({"type":"SimpleItem","command":22,"frame":0,"params":{"lat":1}},)" + wp + "," + wp),
       "takeoff_params.plan: mission.items[0]: params is missing or not an array of 7"},
      {"unlimited.plan",
       plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", mavlink::kCmdNavLoiterUnlim) + "," +
                 waypoint(0, "37.77", "-122.41", "60")),
       "unlimited.plan: mission.items[1] (doJumpId 1): command 17 (an unlimited loiter) comes before this waypoint"},
      // items that move the aircraft without a position visvol can check,
      // and numbers that are no command: refused, never left out unseen
      {"orbit.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 34) + "," + wp),
       "orbit.plan: mission.items[1] (doJumpId 1): command 34 moves the aircraft along a path visvol cannot read "
       "from the file"},
      {"climb.plan", plan_text(wp + "," + waypoint(0, "0", "0", "500", 113) + "," + wp),
       "climb.plan: mission.items[1] (doJumpId 1): command 113 moves the aircraft"},
      // a jump flies the leg back to its target again, unseen in the file
      {"jump.plan", plan_text(wp + "," + waypoint(0, "1", "2", "0", 177) + "," + wp),
       "jump.plan: mission.items[1] (doJumpId 1): command 177 moves the aircraft"},
      {"sethome.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 179) + "," + wp),
       "sethome.plan: mission.items[1] (doJumpId 1): command 179 moves the aircraft"},
      {"script.plan", plan_text(wp + "," + waypoint(0, "0", "0", "0", 42702) + "," + wp),
       "script.plan: mission.items[1] (doJumpId 1): command 42702 moves the aircraft"},
      {"user.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 31000) + "," + wp),
       "user.plan: mission.items[1] (doJumpId 1): command 31000 moves the aircraft"},
      {"unknown.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 50) + "," + wp),
       "unknown.plan: mission.items[1] (doJumpId 1): command 50 is not a command visvol knows to leave the flown "
       "path unchanged"},
      {"negative.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", -1) + "," + wp),
       "negative.plan: mission.items[1] (doJumpId 1): command -1 is not a command visvol knows"},
      {"huge.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 70000) + "," + wp),
       "huge.plan: mission.items[1] (doJumpId 1): command 70000 is not a command visvol knows"},
      // past the NAV range too, only the commands known to leave the path as it is pass
      {"unassigned.plan", plan_text(wp + "," + waypoint(0, "37.78", "-122.42", "60", 12345) + "," + wp),
       "unassigned.plan: mission.items[1] (doJumpId 1): command 12345 is not a command visvol knows"},
      {"current.plan", plan_text(wp + "," + waypoint(0, "0", "0", "0", 224) + "," + wp),
       "current.plan: mission.items[1] (doJumpId 1): command 224 moves the aircraft"},
      {"return.plan", plan_text(wp + "," + waypoint(0, "0", "0", "0", 188) + "," + wp),
       "return.plan: mission.items[1] (doJumpId 1): command 188 moves the aircraft"},
      {"terminate.plan", plan_text(wp + "," + waypoint(0, "0", "0", "0", 185) + "," + wp),
       "terminate.plan: mission.items[1] (doJumpId 1): command 185 moves the aircraft"},
      // a fixed-wing circles while it waits, on a circle the file does not give
      {"delay.plan", plan_text(wp + "," + waypoint(0, "0", "0", "0", 93) + "," + wp),
       "delay.plan: mission.items[1] (doJumpId 1): command 93 moves the aircraft"},
      {"survey.plan", plan_text(wp + R"(,{"type":"ComplexItem","complexItemType":"survey"},)" + wp),
       "survey.plan: mission.items[1]: a ComplexItem (survey): its flown path is not in the file"},
      {"home.plan", plan_text(wp + "," + waypoint(3, "37.78", "-122.42", "60"), "[37.79, -122.43]"),
       "home.plan: mission.items[1] (doJumpId 1): frame 3 (MAV_FRAME_GLOBAL_RELATIVE_ALT, above home) needs the home "
       "altitude: mission.plannedHomePosition is missing or not [latitude, longitude, altitude]"},
      {"where.plan", plan_text(wp + "," + waypoint(0, "97.5", "-122.42", "60")),
       "where.plan: mission.items[1] (doJumpId 1): latitude 97.500000, longitude -122.420000 is not a WGS84 position"},
      {"type.plan", R"({"fileType":"GeoFence","version":1})",
       "type.plan: fileType \"GeoFence\"; a QGroundControl plan"},
      {"version.plan", R"({"fileType":"Plan","version":3,"mission":{}})",
       "version.plan: version 3; this reader knows QGroundControl plan version 1"},
      // messages print the values they name: a nesting this deep would overflow the stack
      {"nested.plan", R"({"fileType":)" + std::string(1000000, '[') + std::string(1000000, ']') + "}",
       "nested.plan: JSON nested deeper than 64 levels"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    Result<PathFile> path = read_path_file(file_with(c.name, c.text), wkt_);
    ASSERT_FALSE(path.ok());
    EXPECT_EQ(path.status().code(), Errc::invalid_argument);
    EXPECT_NE(path.status().message().find(dir_ + "/" + c.message), std::string::npos) << path.status().message();
  }
  // a .plan is in WGS84: without the pack's CRS it cannot become a path
  Result<PathFile> no_crs = read_path_file(file_with("crs.plan", plan_text(wp + "," + wp)));
  ASSERT_FALSE(no_crs.ok());
  EXPECT_NE(no_crs.status().message().find("crs.plan: a .plan is in WGS84"), std::string::npos)
      << no_crs.status().message();
}

}  // namespace
}  // namespace visvol::cli
