// WGS84 positions and heights (tools/visvol/wgs84): EGM96 undulations, a
// missing geoid grid named, each output saying how its positions were
// converted, and a pack CRS in degrees placing nothing.
#include "path_io_fixture.hpp"

namespace visvol::cli {
namespace {

using namespace path_files_test;

TEST(Geoid, EllipsoidalHeightIsOrthometricPlusTheEgm96Undulation) {
  // San Francisco: N about -32 m
  Result<std::vector<Vec3>> sf = orthometric_to_ellipsoidal({{-122.4194, 37.7749, 100.0}});
  ASSERT_TRUE(sf.ok()) << sf.status().message();
  EXPECT_GT((*sf)[0].z() - 100.0, kSfUndulationLowM);
  EXPECT_LT((*sf)[0].z() - 100.0, kSfUndulationHighM);
  EXPECT_DOUBLE_EQ((*sf)[0].x(), -122.4194);  // longitude and latitude kept
  EXPECT_DOUBLE_EQ((*sf)[0].y(), 37.7749);
  // the geoid's low south of India (about -100 m) and its high over New Guinea (about +70 m)
  Result<std::vector<Vec3>> extremes = orthometric_to_ellipsoidal({{78.0, 5.0, 0.0}, {147.0, -6.0, 0.0}});
  ASSERT_TRUE(extremes.ok()) << extremes.status().message();
  EXPECT_LT((*extremes)[0].z(), -90.0);
  EXPECT_GT((*extremes)[0].z(), -110.0);
  EXPECT_GT((*extremes)[1].z(), 50.0);
  EXPECT_LT((*extremes)[1].z(), 90.0);
  // and back
  Result<std::vector<Vec3>> back = ellipsoidal_to_orthometric(*sf);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_NEAR((*back)[0].z(), 100.0, 1e-6);
}

// PROJ_DATA set for the life of a scope (restored after).
class ScopedProjData {
 public:
  explicit ScopedProjData(const std::string& dir) {
    if (const char* old = std::getenv("PROJ_DATA")) old_ = old;
    had_ = std::getenv("PROJ_DATA") != nullptr;
    setenv("PROJ_DATA", dir.c_str(), 1);
  }
  ~ScopedProjData() {
    if (had_) {
      setenv("PROJ_DATA", old_.c_str(), 1);
    } else {
      unsetenv("PROJ_DATA");
    }
  }
  ScopedProjData(const ScopedProjData&) = delete;
  ScopedProjData& operator=(const ScopedProjData&) = delete;

 private:
  std::string old_;
  bool had_ = false;
};

// Without the EGM96 grid no height is converted, and the GeoJSON is not
// written (never orthometric heights labelled ellipsoidal, which is what
// PROJ's default "ballpark" fallback would do): the message names the grid.
// PROJ reads its data folder anew for each context: this one has the
// database but no grid.
TEST_F(PathIo, MissingGeoidGridIsNamedAndNoGeoJsonIsWritten) {
  const std::string proj_dir = dir_ + "/proj";
  std::filesystem::create_directories(proj_dir);
  std::filesystem::copy_file("/usr/share/proj/proj.db", proj_dir + "/proj.db");
  const PathReport r = report(preset("multirotor"));
  const std::string base = dir_ + "/no_grid";
  Result<std::vector<Vec3>> h = Status(Errc::state, "not run");
  Status s;
  std::vector<std::string> written;
  {
    ScopedProjData no_grid(proj_dir);
    h = orthometric_to_ellipsoidal({{-122.4194, 37.7749, 100.0}});
    s = write_path_outputs(base, r, written);
  }
  ASSERT_FALSE(h.ok());
  EXPECT_EQ(h.status().code(), Errc::unsupported);
  EXPECT_NE(h.status().message().find("the EGM96 geoid grid us_nga_egm96_15.tif"), std::string::npos)
      << h.status().message();
  EXPECT_NE(h.status().message().find("proj-data"), std::string::npos) << h.status().message();
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("GeoJSON not written: the EGM96 geoid grid us_nga_egm96_15.tif", 0), 0u) << s.message();
  EXPECT_EQ(written.size(), 3u);
  EXPECT_TRUE(exists(base + ".csv"));
  EXPECT_TRUE(exists(base + ".kml"));
  EXPECT_TRUE(exists(base + ".plan"));
  EXPECT_FALSE(exists(base + ".geojson"));
  EXPECT_EQ(slurp(base + ".csv").find("h_ellipsoidal_m"), std::string::npos);
  // nor is a GeoJSON with heights read
  Result<PathFile> read = Status(Errc::state, "not run");
  const std::string foreign = file_with("foreign.geojson", R"({"type":"LineString","coordinates":)"
                                                           R"([[-122.43,37.79,100.0],[-122.42,37.78,120.0]]})");
  {
    ScopedProjData no_grid(proj_dir);
    read = read_path_file(foreign, wkt_);
  }
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.status().message().find("foreign.geojson: heights: the EGM96 geoid grid"), std::string::npos)
      << read.status().message();
  // and with the grid back, all is well
  EXPECT_TRUE(orthometric_to_ellipsoidal({{-122.4194, 37.7749, 100.0}}).ok());
}

// WGS84 positions say how they were made. From WGS 84 / UTM the change of
// projection is exact; from NAD27 / UTM (the bundled SF North DEM's CRS)
// PROJ shifts the datum, to 7 m with Debian's proj-data (EPSG's figure): the
// outputs name the transformation and its accuracy, and a coarser one than a
// metre gets a note for the operator.
TEST_F(PathIo, WgsPositionsSayHowTheyWereConverted) {
  PathReport r = report(preset("multirotor"));
  Wgs84Conversion exact;
  ASSERT_TRUE(to_wgs84(r.vertices, r.crs_wkt, &exact).ok());
  EXPECT_EQ(exact.accuracy_m, 0.0) << exact.operation;
  EXPECT_EQ(wgs84_accuracy_note(exact), "");
  EXPECT_NE(slurp(write(r, "wgs84") + ".csv").find("in degrees; by Inverse of UTM zone 10N (exact)\n"),
            std::string::npos);

  r.crs_wkt = utm10n_wkt(26710);  // NAD27 / UTM zone 10N
  Wgs84Conversion shift;
  ASSERT_TRUE(to_wgs84(r.vertices, r.crs_wkt, &shift).ok());
  EXPECT_NE(shift.operation.find("NAD27 to WGS 84"), std::string::npos) << shift.operation;
  EXPECT_NE(shift.accuracy_m, 0.0) << "a datum shift is never exact";
  const std::string note = wgs84_accuracy_note(shift);
  // the note where the accuracy is coarser than a metre or not known, only there
  EXPECT_EQ(note.empty(), shift.accuracy_m >= 0 && shift.accuracy_m <= kTrustedWgs84AccuracyM) << note;
  if (!note.empty()) {
    EXPECT_EQ(note.rfind("WGS84 positions by " + shift.describe(), 0), 0u) << note;
  }
  const std::string base = write(r, "nad27");
  EXPECT_NE(slurp(base + ".csv").find("in degrees; by " + shift.describe()), std::string::npos);
  EXPECT_NE(slurp(base + ".kml").find("Positions from the pack's CRS by " + shift.describe()), std::string::npos);
  const nlohmann::json gj = nlohmann::json::parse(slurp(base + ".geojson"));
  const nlohmann::json& p = gj["features"][0]["properties"];
  EXPECT_EQ(p["horizontal_transformation"], shift.operation);
  if (shift.accuracy_m > 0) {
    EXPECT_EQ(p["horizontal_accuracy_m"].get<double>(), shift.accuracy_m);
  }
  // and the NAD27 positions differ from WGS 84 ones by metres, not zero
  Result<std::vector<Vec3>> as_wgs84 = to_wgs84(r.vertices, utm10n_wkt());
  Result<std::vector<Vec3>> as_nad27 = to_wgs84(r.vertices, r.crs_wkt);
  ASSERT_TRUE(as_wgs84.ok() && as_nad27.ok());
  EXPECT_GT(std::abs((*as_wgs84)[0].x() - (*as_nad27)[0].x()), 1e-4) << "degrees: about 9 m";
}

TEST_F(PathIo, APackCrsInDegreesPlacesNothing) {
  // a grid in metres under a geographic CRS (a forged or mislabelled pack):
  // latitude 4182200 was written into a .plan
  PathReport r = report(preset("multirotor"));
  OGRSpatialReference geographic;
  geographic.importFromEPSG(4326);
  char* wkt = nullptr;
  geographic.exportToWkt(&wkt);
  r.crs_wkt = wkt;
  CPLFree(wkt);
  std::vector<std::string> written;
  const Status s = write_path_outputs(dir_ + "/degrees", r, written);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("is not a projected CRS in metres"), std::string::npos) << s.message();
  EXPECT_EQ(written, std::vector<std::string>{dir_ + "/degrees.csv"});
}

}  // namespace
}  // namespace visvol::cli
