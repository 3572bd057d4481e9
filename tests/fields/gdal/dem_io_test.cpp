#include "fields/gdal/dem_io.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "../terrains.hpp"
#include "hostile_rasters.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

std::string temp_name(const std::string& stem) {
  return ::testing::TempDir() + "/" + stem + "_" + std::to_string(::getpid()) + ".tif";
}

TEST(DemIo, RefusesNodataByDefaultCountingThePosts) {
  const Result<Heightfield> hf = read_heightfield(test_data("sf_north_utm10_30m.tif"));
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("2863 posts are nodata"), std::string::npos) << hf.status().message();
}

TEST(DemIo, ReadsSanFranciscoNorthWithPixelCentres) {
  const Result<Heightfield> hf = read_heightfield(test_data("sf_north_utm10_30m.tif"), {NodataPolicy::fill});
  ASSERT_TRUE(hf.ok()) << hf.status().message();
  EXPECT_EQ(hf->nx, 370);
  EXPECT_EQ(hf->ny, 466);
  EXPECT_DOUBLE_EQ(hf->spacing_m, 30.0);
  // The GeoTIFF's corner is (543975, 4191945): the first post is half a pixel in.
  EXPECT_DOUBLE_EQ(hf->origin_x, 543990.0);
  EXPECT_DOUBLE_EQ(hf->origin_y, 4191930.0);
  const HeightRange r = height_range(*hf);
  EXPECT_FLOAT_EQ(r.min_m, 0.0f);
  EXPECT_FLOAT_EQ(r.max_m, 343.0f);
  EXPECT_NE(hf->crs_wkt.find("UTM zone 10N"), std::string::npos);
}

TEST(DemIo, RefusesGeographicDemsSayingToProjectThem) {
  const std::string path = std::string(VISVOL_SHARED_DATA) + "/dem/boulder_srtm3_404x404.asc";
  if (access(path.c_str(), R_OK) != 0) GTEST_SKIP() << path << " not found";
  // It has no CRS at all: the extent and pixel size give the degrees away.
  const Result<Heightfield> hf = read_heightfield(path);
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("degrees"), std::string::npos) << hf.status().message();
  EXPECT_NE(hf.status().message().find("projected"), std::string::npos);
}

TEST(DemIo, MissingFileIsAnIoErrorNamingIt) {
  const Result<Heightfield> hf = read_heightfield("/nonexistent/dem.tif");
  ASSERT_FALSE(hf.ok());
  EXPECT_EQ(hf.status().code(), Errc::io);
  EXPECT_NE(hf.status().message().find("/nonexistent/dem.tif"), std::string::npos);
}

// GDAL's virtual file systems: a DEM in a gzip archive reads; the archive is
// checked as any input (a FIFO there is refused at once, where GDAL would
// block); the network ones are refused before GDAL sees them.
TEST(DemIo, ArchivesReadLocalFilesOnlyAndTheArchiveIsChecked) {
  Heightfield hf = fractal(20, 3);
  hf.crs_wkt.clear();
  const std::string path = temp_name("zipped");
  ASSERT_TRUE(write_geotiff_f32(path, hf, hf.height_m, -9999.0).ok());
  ASSERT_EQ(std::system(("gzip -f " + path).c_str()), 0);
  const Result<Heightfield> back = read_heightfield("/vsigzip/" + path + ".gz");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->height_m, hf.height_m);
  EXPECT_NE(::access((path + ".gz.properties").c_str(), F_OK), 0) << "GDAL wrote beside the archive";
  // a FIFO where GDAL looks for the archive's side file (DEM.tif.prj) is refused too
  const std::string side = path + ".prj";
  ASSERT_EQ(::mkfifo(side.c_str(), 0644), 0);
  const Result<Heightfield> blocked = read_heightfield("/vsigzip/" + path + ".gz");
  std::remove(side.c_str());
  ASSERT_FALSE(blocked.ok());
  EXPECT_NE(blocked.status().message().find(side + ": is a FIFO"), std::string::npos) << blocked.status().message();
  std::remove((path + ".gz").c_str());

  const std::string fifo = temp_name("fifo") + ".gz";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  // braced names nest: the innermost archive is the one checked
  for (const std::string& virtual_path :
       {"/vsigzip/" + fifo, "/vsizip/{" + fifo + "}/dem.tif", "/vsitar//vsigzip/" + fifo + "/dem.tif",
        "/vsizip/{/vsigzip/" + fifo + "}/dem.tif", "/vsizip/{/vsizip/{" + fifo + "}/inner.zip}/dem.tif"}) {
    const Result<Heightfield> f = read_heightfield(virtual_path);
    ASSERT_FALSE(f.ok()) << virtual_path;
    EXPECT_NE(f.status().message().find(fifo + ": is a FIFO"), std::string::npos) << f.status().message();
  }
  std::remove(fifo.c_str());
  const Result<Heightfield> unclosed = read_heightfield("/vsizip/{/vsizip/{" + fifo + "}/inner.zip/dem.tif");
  ASSERT_FALSE(unclosed.ok());
  EXPECT_NE(unclosed.status().message().find("no '}' closes"), std::string::npos) << unclosed.status().message();

  for (const char* remote : {"/vsicurl/http://127.0.0.1:9/dem.tif", "/vsis3/bucket/dem.tif", "/vsistdin/"}) {
    const Result<Heightfield> r = read_heightfield(remote);
    ASSERT_FALSE(r.ok()) << remote;
    EXPECT_EQ(r.status().code(), Errc::invalid_argument) << remote;
    EXPECT_NE(r.status().message().find("not a GDAL file system visvol reads"), std::string::npos)
        << r.status().message();
  }
}

TEST(DemIo, GeoTiffRoundTripKeepsGridAndValues) {
  Heightfield hf = fractal(20, 3);
  hf.crs_wkt.clear();
  const std::string path = temp_name("roundtrip");
  ASSERT_TRUE(write_geotiff_f32(path, hf, hf.height_m, -9999.0).ok());
  const Result<Heightfield> back = read_heightfield(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->nx, 20);
  EXPECT_DOUBLE_EQ(back->origin_x, hf.origin_x);
  EXPECT_DOUBLE_EQ(back->origin_y, hf.origin_y);
  EXPECT_DOUBLE_EQ(back->spacing_m, hf.spacing_m);
  EXPECT_EQ(back->height_m, hf.height_m);
  std::remove(path.c_str());
}

TEST(DemIo, RefusesNodataPostsNamingTheFirst) {
  Heightfield hf = flat(12);
  hf.at(5, 7) = -9999.0f;
  hf.at(6, 7) = -9999.0f;
  const std::string path = temp_name("nodata");
  ASSERT_TRUE(write_geotiff_f32(path, hf, hf.height_m, -9999.0).ok());
  const Result<Heightfield> back = read_heightfield(path);
  ASSERT_FALSE(back.ok());
  EXPECT_NE(back.status().message().find("2 posts"), std::string::npos) << back.status().message();
  EXPECT_NE(back.status().message().find("(5, 7)"), std::string::npos);
  std::remove(path.c_str());
}

TEST(DemIo, FillsNodataHolesWhenAsked) {
  Heightfield hf = flat(12);
  hf.at(5, 7) = -9999.0f;
  const std::string path = temp_name("fill");
  ASSERT_TRUE(write_geotiff_f32(path, hf, hf.height_m, -9999.0).ok());
  const Result<Heightfield> back = read_heightfield(path, {NodataPolicy::fill});
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_NEAR(back->at(5, 7), 100.0f, 1e-3f);  // surrounded by 100 m posts
  std::remove(path.c_str());
}

TEST(DemIo, RefusesToFillAMostlyEmptyRaster) {
  // A fuzzer found that filling a sparse raster searched for hours.
  Heightfield hf = flat(12);
  for (std::size_t n = 0; n < hf.size() * 3 / 4; ++n) hf.height_m[n] = -9999.0f;
  const std::string path = temp_name("sparse");
  ASSERT_TRUE(write_geotiff_f32(path, hf, hf.height_m, -9999.0).ok());
  const Result<Heightfield> back = read_heightfield(path, {NodataPolicy::fill});
  ASSERT_FALSE(back.ok());
  EXPECT_NE(back.status().message().find("too few to fill"), std::string::npos) << back.status().message();
  std::remove(path.c_str());
}

TEST(DemIo, RefusesRastersOverThePostLimitBeforeReading) {
  DemReadOptions options;
  options.max_posts = 1000;
  const Result<Heightfield> hf = read_heightfield(test_data("sf_north_utm10_30m.tif"), options);
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("more than the 1000"), std::string::npos);
}

TEST(DemIo, OnlyAllowedDriversOpen) {
  DemReadOptions options;
  options.drivers = {"AAIGrid"};
  const Result<Heightfield> hf = read_heightfield(test_data("sf_north_utm10_30m.tif"), options);
  ASSERT_FALSE(hf.ok());
  EXPECT_EQ(hf.status().code(), Errc::io);
}

TEST(DemIo, WeightsRasterMustMatchTheGrid) {
  const Heightfield hf = flat(12);
  const std::string path = temp_name("weights");
  const Heightfield small = flat(8);
  ASSERT_TRUE(write_geotiff_f32(path, small, std::vector<float>(small.size(), 0.5f), -1).ok());
  const Result<std::vector<float>> w = read_raster_like(path, hf);
  ASSERT_FALSE(w.ok());
  EXPECT_NE(w.status().message().find("8 x 8"), std::string::npos);
  std::remove(path.c_str());
}

TEST(DemIo, FailedWriteLeavesNoFile) {
  const Heightfield hf = flat(4);
  const Status st = write_geotiff_u8("/nonexistent-dir/out.tif", hf, std::vector<std::uint8_t>(16, 1), 255);
  EXPECT_FALSE(st.ok());
}

TEST(DemIo, UnknownVerticalUnitIsRefusedNamingIt) {
  TiffSpec spec;
  spec.unit = "furlong";
  const std::string path = write_hostile_tiff("furlong", spec);
  const Result<Heightfield> hf = read_heightfield(path);
  ASSERT_FALSE(hf.ok());
  EXPECT_EQ(hf.status().code(), Errc::invalid_argument);
  EXPECT_NE(hf.status().message().find(path + ": heights are in 'furlong', a unit visvol does not know"),
            std::string::npos)
      << hf.status().message();
  std::remove(path.c_str());
}

TEST(DemIo, KnownVerticalUnitsConvertToMetres) {
  const struct {
    const char* unit;
    double to_m;
  } cases[] = {{"metre", 1.0}, {"Meters", 1.0}, {"ft", 0.3048}, {"US survey foot", 1200.0 / 3937.0}, {"", 1.0}};
  for (const auto& c : cases) {
    TiffSpec spec;
    spec.unit = c.unit;
    const std::string path = write_hostile_tiff("unit", spec);
    const Result<Heightfield> hf = read_heightfield(path);
    ASSERT_TRUE(hf.ok()) << c.unit << ": " << hf.status().message();
    EXPECT_NEAR(hf->at(0, 0), 100.0 * c.to_m, 1e-3) << c.unit;
    std::remove(path.c_str());
  }
}

// Each geotransform a DEM should not have, and what the refusal says.
struct BadGrid {
  const char* what;
  double gt[6];
  const char* message;
};

const BadGrid kBadGrids[] = {
    {"rotated", {500000, 30, 2, 4001000, 2, -30}, "has rotation or shear terms"},
    {"sheared", {500000, 30, 0, 4001000, 5, -30}, "has rotation or shear terms"},
    {"south-up", {500000, 30, 0, 4000000, 0, 30}, "is not north-up"},
    {"negative width", {500000, -30, 0, 4001000, 0, -30}, "is not north-up"},
    {"zero width", {500000, 0, 0, 4001000, 0, -30}, "has no georeference"},  // GeoTIFF keeps none
    {"NaN term", {500000, 30, 0, NAN, 0, -30}, "has a term that is not finite"},
    {"huge cells", {500000, 1e30, 0, 4001000, 0, -1e30}, "is outside 0.01..100000 m"},
    {"tiny cells", {500000, 1e-9, 0, 4001000, 0, -1e-9}, "is outside 0.01..100000 m"},
    {"far origin", {1e300, 30, 0, 4001000, 0, -30}, "reaches beyond +-100000000 m"},
    {"far south", {500000, 30, 0, -2e8, 0, -30}, "reaches beyond +-100000000 m"},
};

TEST(DemIo, RefusesGeotransformsNoDemShouldHaveSayingWhatWasFound) {
  for (const BadGrid& bad : kBadGrids) {
    TiffSpec spec;
    std::copy(bad.gt, bad.gt + 6, spec.gt);
    const std::string path = write_hostile_tiff("bad_grid", spec);
    const Result<Heightfield> hf = read_heightfield(path);
    ASSERT_FALSE(hf.ok()) << bad.what;
    EXPECT_EQ(hf.status().code(), Errc::invalid_argument) << bad.what;
    EXPECT_EQ(hf.status().message().rfind(path + ": ", 0), 0u) << bad.what << ": " << hf.status().message();
    EXPECT_NE(hf.status().message().find(bad.message), std::string::npos) << bad.what << ": " << hf.status().message();
    std::remove(path.c_str());
  }
}

TEST(DemIo, GridsAtTheEdgesOfTheRangesRead) {
  for (const double cell_m : {kMinPostSpacingM, kMaxPostSpacingM}) {
    TiffSpec spec;
    spec.gt[1] = cell_m;
    spec.gt[5] = -cell_m;
    spec.gt[3] = 4001000;
    const std::string path = write_hostile_tiff("edge_grid", spec);
    EXPECT_TRUE(read_heightfield(path).ok()) << cell_m;
    std::remove(path.c_str());
  }
}

}  // namespace
}  // namespace visvol::fields
