// Small hostile DEMs for the reader's tests: GeoTIFFs written through GDAL
// with any geotransform and band unit, and ESRI ASCII grids as text (GDAL
// writes no bad cell, so those are typed).
#pragma once

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace visvol::fields::testing {

inline std::string hostile_path(const std::string& stem, const std::string& ext) {
  return ::testing::TempDir() + "/" + stem + "_" + std::to_string(::getpid()) + ext;
}

struct TiffSpec {
  int n = 12;                                       // posts a side
  double gt[6] = {500000, 30, 0, 4001000, 0, -30};  // GDAL order
  const char* unit = nullptr;                       // band unit; none when null
  int epsg = 32633;                                 // 0: no CRS
};

// A float GeoTIFF of gently sloping heights (100 m and up) as `spec` says.
inline std::string write_hostile_tiff(const std::string& stem, const TiffSpec& spec) {
  const std::string path = hostile_path(stem, ".tif");
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), spec.n, spec.n, 1, GDT_Float32, nullptr);
  EXPECT_NE(ds, nullptr);
  if (!ds) return path;
  double gt[6];
  std::copy(spec.gt, spec.gt + 6, gt);
  ds->SetGeoTransform(gt);
  if (spec.epsg != 0) {
    OGRSpatialReference srs;
    srs.importFromEPSG(spec.epsg);
    ds->SetSpatialRef(&srs);
  }
  GDALRasterBand* band = ds->GetRasterBand(1);
  if (spec.unit) band->SetUnitType(spec.unit);
  std::vector<float> h(static_cast<std::size_t>(spec.n) * static_cast<std::size_t>(spec.n));
  for (std::size_t k = 0; k < h.size(); ++k) h[k] = 100.0f + static_cast<float>(k % 7);
  EXPECT_EQ(band->RasterIO(GF_Write, 0, 0, spec.n, spec.n, h.data(), spec.n, spec.n, GDT_Float32, 0, 0), CE_None);
  GDALClose(GDALDataset::ToHandle(ds));
  return path;
}

// An n x n ESRI ASCII grid with a 30 m cell; `cell` replaces the text of
// cell (5, 3) (column, row) when not empty.
inline std::string asc_text(int n, const std::string& cellsize = "30", const std::string& xll = "500000",
                            const std::string& cell = "") {
  std::ostringstream s;
  s << "ncols " << n << "\nnrows " << n << "\nxllcorner " << xll << "\nyllcorner 4000000\ncellsize " << cellsize
    << "\nNODATA_value -9999\n";
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      s << (i ? " " : "");
      if (i == 5 && j == 3 && !cell.empty()) {
        s << cell;
      } else {
        s << 100 + (i * 7 + j * 3) % 50;
      }
    }
    s << "\n";
  }
  return s.str();
}

inline std::string write_text(const std::string& stem, const std::string& ext, const std::string& text) {
  const std::string path = hostile_path(stem, ext);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

}  // namespace visvol::fields::testing
