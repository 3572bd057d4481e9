#include "fields/gdal/dem_import.hpp"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "../terrains.hpp"
#include "hostile_rasters.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

std::string shared(const std::string& name) { return std::string(VISVOL_SHARED_DATA) + "/dem/" + name; }
bool have(const std::string& path) { return access(path.c_str(), R_OK) == 0; }

ImportOptions filling() {
  ImportOptions o;
  o.nodata = NodataPolicy::fill;
  return o;
}

TEST(DemImport, EveryRealDemImports) {
  struct Case {
    std::string file;
    std::string assume;
    std::string crs;  // part of the output CRS name
  };
  const std::vector<Case> cases = {
      {"sf_north_utm10_30m.tif", "", "UTM zone 10N"},
      {"sf_north_usgs24k.dem", "", ""},
      {"whitebox_dem.tif", "", ""},
      {"N50E008.hgt", "", "UTM zone 32N"},
      {"boulder_srtm3_404x404.asc", "EPSG:4326", "UTM zone 13N"},
      {"grass_viewshed_reference/elevation.ascii", "", "local metres"},
  };
  int imported = 0;
  for (const Case& c : cases) {
    if (!have(shared(c.file))) continue;
    ImportOptions o = filling();
    o.assume_srs = c.assume;
    ImportReport rep;
    const Result<Heightfield> hf = import_dem(shared(c.file), o, &rep);
    ASSERT_TRUE(hf.ok()) << c.file << ": " << hf.status().message();
    EXPECT_TRUE(validate(*hf, c.file).ok());
    EXPECT_NE(rep.output_crs.find(c.crs), std::string::npos) << c.file << ": " << rep.output_crs;
    ++imported;
  }
  if (imported == 0) GTEST_SKIP() << "shared/data not found";
  EXPECT_EQ(imported, 6);
}

TEST(DemImport, GeographicSrtmIsProjectedToItsUtmZone) {
  if (!have(shared("N50E008.hgt"))) GTEST_SKIP() << "shared/data not found";
  ImportReport rep;
  const Result<Heightfield> hf = import_dem(shared("N50E008.hgt"), filling(), &rep);
  ASSERT_TRUE(hf.ok()) << hf.status().message();
  EXPECT_TRUE(rep.warped);
  EXPECT_NE(rep.steps.find("EPSG:32632"), std::string::npos);
  // One degree of latitude is about 111 km; the grid spans it.
  EXPECT_NEAR(hf->ny * hf->spacing_m, 111000.0, 3000.0);
  const HeightRange r = height_range(*hf);
  EXPECT_GT(r.min_m, 50.0);   // Taunus valleys
  EXPECT_LT(r.max_m, 900.0);  // Grosser Feldberg, 878 m
}

TEST(DemImport, GridWithoutCrsInDegreesNeedsAssumeSrs) {
  if (!have(shared("boulder_srtm3_404x404.asc"))) GTEST_SKIP() << "shared/data not found";
  const Result<Heightfield> hf = import_dem(shared("boulder_srtm3_404x404.asc"), filling());
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("--assume-srs"), std::string::npos) << hf.status().message();
}

std::string write_test_raster(const std::string& stem, const Heightfield& hf, const char* unit, double pixel_y = 0) {
  const std::string path = ::testing::TempDir() + "/" + stem + "_" + std::to_string(getpid()) + ".tif";
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), hf.nx, hf.ny, 1, GDT_Float32, nullptr);
  const double py = pixel_y != 0 ? pixel_y : hf.spacing_m;
  double gt[6] = {hf.origin_x - 0.5 * hf.spacing_m, hf.spacing_m, 0, hf.origin_y + 0.5 * py, 0, -py};
  ds->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.importFromEPSG(32633);
  ds->SetSpatialRef(&srs);
  GDALRasterBand* band = ds->GetRasterBand(1);
  if (unit) band->SetUnitType(unit);
  EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, hf.nx, hf.ny, const_cast<float*>(hf.height_m.data()), hf.nx, hf.ny,
                           GDT_Float32, 0, 0),
            CE_None);
  GDALClose(ds);
  return path;
}

TEST(DemImport, FeetBecomeMetres) {
  const Heightfield hf = flat(10, 30.0);  // 100 "ft"
  const std::string path = write_test_raster("feet", hf, "ft");
  ImportReport rep;
  const Result<Heightfield> got = import_dem(path, ImportOptions{}, &rep);
  ASSERT_TRUE(got.ok()) << got.status().message();
  EXPECT_NEAR(got->at(3, 3), 30.48f, 1e-4f);
  EXPECT_NE(rep.steps.find("to metres"), std::string::npos);
  std::remove(path.c_str());
}

TEST(DemImport, CropKeepsTheBoxWithoutResampling) {
  Heightfield hf = fractal(40, 3, 30.0);
  const std::string path = write_test_raster("crop", hf, nullptr);
  ImportOptions o;
  // Pixel edges: posts 10..19 in x, rows 5..14 in y.
  o.crop = BoundingBox{hf.x_of(10) - 15, hf.y_of(14) - 15, hf.x_of(19) + 15, hf.y_of(5) + 15};
  const Result<Heightfield> got = import_dem(path, o);
  ASSERT_TRUE(got.ok()) << got.status().message();
  EXPECT_EQ(got->nx, 10);
  EXPECT_EQ(got->ny, 10);
  EXPECT_DOUBLE_EQ(got->origin_x, hf.x_of(10));
  EXPECT_DOUBLE_EQ(got->origin_y, hf.y_of(5));
  EXPECT_EQ(got->at(0, 0), hf.at(10, 5));
  EXPECT_EQ(got->at(9, 9), hf.at(19, 14));
  std::remove(path.c_str());
}

TEST(DemImport, ResamplesToASpacingAndSquaresPixels) {
  const Heightfield hf = fractal(40, 5, 30.0);
  const std::string path = write_test_raster("resample", hf, nullptr);
  ImportOptions o;
  o.spacing_m = 60.0;
  const Result<Heightfield> got = import_dem(path, o);
  ASSERT_TRUE(got.ok()) << got.status().message();
  EXPECT_DOUBLE_EQ(got->spacing_m, 60.0);
  EXPECT_EQ(got->nx, 20);
  std::remove(path.c_str());
  // Pixels 30 x 33 m become square.
  const std::string oblong = write_test_raster("oblong", hf, nullptr, 33.0);
  ImportReport rep;
  const Result<Heightfield> sq = import_dem(oblong, ImportOptions{}, &rep);
  ASSERT_TRUE(sq.ok()) << sq.status().message();
  EXPECT_NEAR(sq->spacing_m, std::sqrt(30.0 * 33.0), 1e-6);
  EXPECT_TRUE(rep.warped);
  std::remove(oblong.c_str());
}

TEST(DemImport, ExplicitTargetCrs) {
  const Heightfield hf = fractal(20, 5, 30.0);
  const std::string path = write_test_raster("tsrs", hf, nullptr);
  // The neighbouring zone: the grid turns, its corners have no data to fill from the edges.
  ImportOptions o = filling();
  o.target_srs = "EPSG:32634";
  ImportReport rep;
  const Result<Heightfield> got = import_dem(path, o, &rep);
  ASSERT_TRUE(got.ok()) << got.status().message();
  EXPECT_NE(rep.output_crs.find("UTM zone 34N"), std::string::npos);
  o.target_srs = "EPSG:4326";
  const Result<Heightfield> geo = import_dem(path, o);
  ASSERT_FALSE(geo.ok());
  EXPECT_NE(geo.status().message().find("not a projected CRS"), std::string::npos);
  o.target_srs = "EPSG:999999";
  EXPECT_FALSE(import_dem(path, o).ok());
  std::remove(path.c_str());
}

TEST(DemImport, RejectsBadOptionsByName) {
  ImportOptions o;
  o.spacing_m = -5;
  EXPECT_NE(validate(o).message().find("spacing"), std::string::npos);
  o = ImportOptions{};
  o.crop = BoundingBox{10, 10, 5, 20};
  EXPECT_NE(validate(o).message().find("crop"), std::string::npos);
  o = ImportOptions{};
  o.resampling = "magic";
  EXPECT_NE(validate(o).message().find("resampling"), std::string::npos);
}

TEST(DemImport, UtmZones) {
  EXPECT_EQ(utm_srs_for(8.5, 50.5), "EPSG:32632");
  EXPECT_EQ(utm_srs_for(-105.5, 40.1), "EPSG:32613");
  EXPECT_EQ(utm_srs_for(-122.4, 37.8), "EPSG:32610");
  EXPECT_EQ(utm_srs_for(151.2, -33.9), "EPSG:32756");
  EXPECT_EQ(utm_srs_for(180.0, 0.0), "EPSG:32660");
}

TEST(DemImport, ANegativeCellSizeIsRefusedNotWarpedUpsideDown) {
  // Import used to warp this grid (pixel -30 x +30) north-up: rotated 180
  // degrees and moved by the grid's size, with exit 0.
  const std::string path = write_text("negative_cell", ".asc", asc_text(40, "-30"));
  ImportOptions o;
  o.assume_srs = "EPSG:32633";
  const Result<Heightfield> hf = import_dem(path, o);
  ASSERT_FALSE(hf.ok());
  EXPECT_EQ(hf.status().code(), Errc::invalid_argument);
  EXPECT_NE(hf.status().message().find(path + ": pixel size -30 x 30"), std::string::npos) << hf.status().message();
  EXPECT_NE(hf.status().message().find("not north-up"), std::string::npos);
  // --area asks for the same grid first: refused the same way.
  EXPECT_FALSE(import_grid(path, o).ok());
  std::remove(path.c_str());
}

// A CRS is text (EPSG:, WKT, PROJ): GDAL would read a file or fetch a URL
// named there; both are refused as CRSs it does not know.
TEST(DemImport, ACrsThatNamesAFileOrAUrlIsRefused) {
  const std::string path = write_text("crs_text", ".asc", asc_text(40, "30"));
  const std::string prj = write_text("crs_file", ".prj", "PROJCS[\"WGS 84 / UTM zone 33N\"]");
  for (const std::string& text : {prj, std::string("http://127.0.0.1:9/crs.prj")}) {
    ImportOptions o;
    o.assume_srs = text;
    const Result<Heightfield> hf = import_dem(path, o);
    ASSERT_FALSE(hf.ok()) << text;
    EXPECT_NE(hf.status().message().find("--assume-srs '" + text + "' is not a CRS GDAL knows"), std::string::npos)
        << hf.status().message();
  }
  ImportOptions good;
  good.assume_srs = "EPSG:32633";
  EXPECT_TRUE(import_dem(path, good).ok());
  std::remove(prj.c_str());
  std::remove(path.c_str());
}

TEST(DemImport, RotatedAndAbsurdGridsAreRefusedBeforeAnyWarp) {
  const struct {
    std::string cellsize, xll, message;
  } cases[] = {{"1e30", "500000", "outside 0.01..100000 m"},
               {"1e-9", "500000", "outside 0.01..100000 m"},
               {"30", "1e300", "reaches beyond +-100000000 m"}};
  for (const auto& c : cases) {
    const std::string path = write_text("absurd_grid", ".asc", asc_text(40, c.cellsize, c.xll));
    ImportOptions o;
    o.assume_srs = "EPSG:32633";
    o.spacing_m = 30;  // a warp would follow
    const Result<Heightfield> hf = import_dem(path, o);
    ASSERT_FALSE(hf.ok()) << c.cellsize << " " << c.xll;
    EXPECT_NE(hf.status().message().find(c.message), std::string::npos) << hf.status().message();
    std::remove(path.c_str());
  }
  TiffSpec spec;
  spec.gt[2] = 3;  // row rotation
  const std::string rotated = write_hostile_tiff("rotated", spec);
  const Result<Heightfield> hf = import_dem(rotated, ImportOptions{});
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("rotation or shear"), std::string::npos) << hf.status().message();
  std::remove(rotated.c_str());
}

TEST(DemImport, GeographicGridsOffTheEarthAreRefused) {
  TiffSpec spec;
  spec.epsg = 4326;
  const double off_earth[][6] = {{8, 0.001, 0, 95, 0, -0.001},  // north of the pole
                                 {8, 5, 0, 50, 0, -5},          // 5 degree pixels
                                 {8, 1e-9, 0, 50, 0, -1e-9}};   // nanodegree pixels
  for (const auto& gt : off_earth) {
    std::copy(gt, gt + 6, spec.gt);
    const std::string path = write_hostile_tiff("off_earth", spec);
    const Result<Heightfield> hf = import_dem(path, ImportOptions{});
    ASSERT_FALSE(hf.ok()) << gt[1] << " " << gt[3];
    EXPECT_TRUE(hf.status().message().find("not on Earth") != std::string::npos ||
                hf.status().message().find("outside 1e-07..1 degrees") != std::string::npos)
        << hf.status().message();
    std::remove(path.c_str());
  }
}

TEST(DemImport, AnOversizedWarpIsRefusedBeforeWarping) {
  // 40 x 40 posts of 30 m at 1 cm would be 120000 posts a side: the red team's
  // "--spacing 3" on an SRTM tile warped for a minute and 3.6 GB before this.
  const std::string path = write_text("oversized", ".asc", asc_text(40));
  ImportOptions o;
  o.assume_srs = "EPSG:32633";
  o.spacing_m = 0.01;
  const Result<Heightfield> hf = import_dem(path, o);
  ASSERT_FALSE(hf.ok());
  EXPECT_NE(hf.status().message().find("would be 120000 x 120000 posts at 0.01 m spacing"), std::string::npos)
      << hf.status().message();
  o.spacing_m = 1;  // 1200 x 1200, over a small post budget
  o.max_posts = 1000000;
  const Result<Heightfield> over = import_dem(path, o);
  ASSERT_FALSE(over.ok());
  EXPECT_NE(over.status().message().find("1200 x 1200 posts"), std::string::npos) << over.status().message();
  o.max_posts = 2000000;
  EXPECT_TRUE(import_dem(path, o).ok());
  std::remove(path.c_str());
}

TEST(DemImport, SpacingOutsideItsRangeIsRefusedByName) {
  ImportOptions o;
  for (const double bad : {1e-9, 1e6, -1.0, std::nan("")}) {
    o.spacing_m = bad;
    EXPECT_NE(validate(o).message().find("neither 0 (keep) nor in 0.01..100000 m"), std::string::npos)
        << bad << ": " << validate(o).message();
  }
  o.spacing_m = 0;
  EXPECT_TRUE(validate(o).ok());
}

TEST(DemImport, AFileWithoutAVerticalUnitSaysItsHeightsAreTakenAsMetres) {
  const std::string path = write_hostile_tiff("no_unit", TiffSpec{});
  ImportReport rep;
  ASSERT_TRUE(import_dem(path, ImportOptions{}, &rep).ok());
  EXPECT_NE(rep.steps.find("heights taken as metres (the file names no vertical unit)"), std::string::npos)
      << rep.steps;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace visvol::fields
