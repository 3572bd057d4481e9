// What the path files' tests share (path_io_test, path_write_test, wgs84_test):
// a UTM 10N pack CRS, a report over San Francisco to write, file helpers.
#pragma once

#include "path_io.hpp"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace visvol::cli::path_files_test {

// EGM96's geoid undulation in San Francisco is about -32 m.
inline constexpr double kSfUndulationLowM = -34.0, kSfUndulationHighM = -30.0;

inline std::string utm10n_wkt(int epsg = 32610) {
  OGRSpatialReference srs;
  EXPECT_EQ(srs.importFromEPSG(epsg), OGRERR_NONE);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string out = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  return out;
}

inline std::string slurp(const std::string& file) {
  std::ifstream in(file);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline bool exists(const std::string& file) { return std::filesystem::exists(file); }

class PathIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/path_io_" + std::to_string(getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::create_directories(dir_);
    wkt_ = utm10n_wkt();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A path over San Francisco (UTM 10N): heights above the DEM's datum, the
  // ground 20 m below the start and 15 m below the end.
  PathReport report(const rt::VehicleEnvelope& vehicle) const {
    PathReport r;
    r.vertices = {{550100, 4182600, 250}, {550400, 4182300, 262.5}, {550700, 4182000, 241}, {551050, 4181700, 230}};
    for (std::size_t i = 0; i < r.vertices.size(); ++i) r.per_vertex.push_back({0.1 * static_cast<double>(i), 50.0});
    r.objective = "hide";
    r.model = "articulated";
    r.pack = "sf.vvp";
    r.crs_wkt = wkt_;
    r.home_ground_m = 230;
    r.land_ground_m = 215;
    r.vehicle = vehicle;
    return r;
  }

  std::string write(const PathReport& r, const std::string& name = "path") {
    const std::string base = dir_ + "/" + name;
    std::vector<std::string> written;
    const Status s = write_path_outputs(base, r, written);
    EXPECT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(written.size(), 4u);
    return base;
  }

  std::string file_with(const std::string& name, const std::string& text) const {
    const std::string f = dir_ + "/" + name;
    std::ofstream(f) << text;
    return f;
  }

  std::string dir_, wkt_;
};

inline rt::VehicleEnvelope preset(const char* name) {
  Result<rt::VehicleEnvelope> v = rt::vehicle_preset(name);
  EXPECT_TRUE(v.ok());
  return *v;
}

inline void expect_same_points(const std::vector<Vec3>& got, const std::vector<Vec3>& want, double tolerance_m) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[i][k], want[i][k], tolerance_m) << "point " << i << ", axis " << k;
  }
}

// A .plan's mission item i, and a position item's fields.
inline const nlohmann::json& item(const nlohmann::json& plan, std::size_t i) { return plan["mission"]["items"][i]; }

inline void expect_position(const nlohmann::json& it, const Vec3& lon_lat, double altitude_m) {
  EXPECT_EQ(it["type"], "SimpleItem");
  EXPECT_EQ(it["frame"], mavlink::kFrameGlobal);
  EXPECT_EQ(it["autoContinue"], true);
  ASSERT_EQ(it["params"].size(), 7u);
  EXPECT_NEAR(it["params"][4].get<double>(), lon_lat.y(), 1e-9);
  EXPECT_NEAR(it["params"][5].get<double>(), lon_lat.x(), 1e-9);
  EXPECT_DOUBLE_EQ(it["params"][6].get<double>(), altitude_m);
}

}  // namespace visvol::cli::path_files_test
