// Terrain in and rasters out through GDAL (offline tools only: the console
// never links GDAL).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "fields/heightfield.hpp"

namespace visvol::fields {

// What a heightfield's grid may be, in metres: posts closer than 1 cm or
// farther apart than 100 km are no terrain model, and a coordinate beyond
// 1e8 m lies outside every projected CRS on Earth (UTM northings reach 1e7 m).
inline constexpr double kMinPostSpacingM = 0.01;
inline constexpr double kMaxPostSpacingM = 1.0e5;
inline constexpr double kMaxCoordinateM = 1.0e8;
// The same for a geographic source's pixels, in degrees (about 1 cm and 111 km).
inline constexpr double kMinPixelDeg = 1.0e-7;
inline constexpr double kMaxPixelDeg = 1.0;

struct DemInfo {
  std::string driver;  // GDAL driver short name ("GTiff", "USGSDEM", ...)
  int nx = 0, ny = 0;
  double geotransform[6] = {0, 1, 0, 0, 0, -1};
  std::string crs_wkt;  // empty when the file has none
  std::string crs_name;
  bool geographic = false;    // degrees: must be projected before use
  double linear_unit_m = 1;   // metres per horizontal CRS unit
  std::string vertical_unit;  // band unit as GDAL reports it ("m", "ft", "")
  double vertical_to_m = 1;   // factor applied to heights
  bool has_nodata = false;
  double nodata = 0;
};

// Reads the header of a raster (any GDAL raster driver, or only `drivers`).
Result<DemInfo> read_dem_info(const std::string& path);
Result<DemInfo> read_dem_info(const std::string& path, const std::vector<std::string>& drivers);

enum class NodataPolicy {
  refuse,  // a nodata or NaN post is an error naming the first one
  fill,    // fill holes by inverse-distance interpolation from their edges (GDALFillNodata)
};

// The formats visvol reads terrain from (GDAL short names).
inline const std::vector<std::string>& dem_drivers() {
  static const std::vector<std::string> names{"GTiff", "AAIGrid", "GRASSASCIIGrid", "USGSDEM", "SRTMHGT", "DTED"};
  return names;
}

struct DemReadOptions {
  DemReadOptions() = default;
  DemReadOptions(NodataPolicy policy) : nodata(policy) {}  // NOLINT: {NodataPolicy::fill} reads well

  NodataPolicy nodata = NodataPolicy::refuse;
  // GDAL drivers allowed to open the file; empty: any raster driver.
  std::vector<std::string> drivers;
  // Rasters with more posts than this are refused before reading (1 GiB of float).
  std::size_t max_posts = std::size_t{1} << 28;
};

// Reads band 1 of a raster as a heightfield in metres. Refuses, naming the
// file and the problem: geographic CRSs (or a raster with no CRS whose extent
// and pixel size look like degrees), rotated or non-square pixels, nodata or
// NaN posts (unless filled).
Result<Heightfield> read_heightfield(const std::string& path, const DemReadOptions& options = {});

// Reads band 1 of a raster as floats that must cover exactly `like`'s grid
// (same size); used for observer weights.
Result<std::vector<float>> read_raster_like(const std::string& path, const Heightfield& like);

// Band 1 as it is: values and which of them are data (not nodata or NaN).
struct RasterBand {
  int nx = 0, ny = 0;
  std::vector<double> value;
  std::vector<std::uint8_t> valid;  // 1 data, 0 nodata or NaN
};
Result<RasterBand> read_band(const std::string& path);

// The short name of a CRS given as WKT ("NAD27 / UTM zone 10N"), or
// "local metres" for an empty WKT.
std::string crs_name(const std::string& wkt);

// Writes a one-band raster on `like`'s grid as a GeoTIFF, through a temporary
// file renamed into place (a crash never leaves a torn file).
Status write_geotiff_u8(const std::string& path, const Heightfield& like, const std::vector<std::uint8_t>& values,
                        int nodata);
Status write_geotiff_f32(const std::string& path, const Heightfield& like, const std::vector<float>& values,
                         double nodata);

}  // namespace visvol::fields
