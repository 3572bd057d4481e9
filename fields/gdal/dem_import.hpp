// Terrain import: any DEM visvol reads (GeoTIFF, SRTM .hgt, USGS .dem, ESRI
// and GRASS ASCII grids, DTED) to a heightfield in metres on a square grid in a
// projected CRS.
//
// Geographic DEMs are projected to the UTM zone of their centre (or to the CRS
// the user gives); non-square pixels and a requested spacing are resampled
// (bilinear by default); a crop keeps a bounding box; the vertical unit of the
// source band is honoured (feet become metres); nodata is refused or filled.
// All through GDAL (gdalwarp and gdal_translate as a library).
#pragma once

#include <optional>
#include <string>

#include "base/status.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/heightfield.hpp"

namespace visvol::fields {

struct BoundingBox {
  double xmin, ymin, xmax, ymax;  // in the output CRS, metres
};

struct ImportOptions {
  NodataPolicy nodata = NodataPolicy::refuse;
  std::string target_srs;  // "EPSG:32632", WKT or PROJ; empty: keep a projected CRS, UTM for degrees
  std::string assume_srs;  // CRS of a file that has none (e.g. an ESRI grid without .prj)
  double spacing_m = 0;    // output post spacing; 0: keep (or GDAL's choice when projecting)
  std::optional<BoundingBox> crop;
  std::string resampling = "bilinear";  // near, bilinear, cubic, average
  std::size_t max_posts = std::size_t{1} << 28;
  // Why max_posts is what it is, for the refusal ("--max-memory 8192 MiB"); empty: the format's limit.
  std::string max_posts_reason;
};

Status validate(const ImportOptions& options);

struct ImportReport {
  DemInfo source;          // the file as it is
  std::string output_crs;  // name of the output CRS
  bool warped = false;     // reprojected or resampled
  bool cropped = false;
  std::string steps;  // what was done, for people ("projected to WGS 84 / UTM zone 32N ...")
};

// The UTM zone CRS ("EPSG:326zz" or "EPSG:327zz") for a longitude and latitude.
std::string utm_srs_for(double lon_deg, double lat_deg);

Result<Heightfield> import_dem(const std::string& path, const ImportOptions& options, ImportReport* report = nullptr);

// The grid import_dem makes of a whole DEM (options.crop ignored), known from
// its header alone: nothing is warped or read.
struct ImportGrid {
  double spacing_m = 0;  // post spacing of the import
  // True when import keeps the source's pixels (no reprojection, no
  // resampling): a crop then keeps whole pixels, on pixel edges at
  // edge_x + n * pixel_x_m and edge_y - n * pixel_y_m. False: the warp puts
  // the grid's north-west corner on the crop's and lays whole posts from it.
  bool aligned = false;
  double edge_x = 0, edge_y = 0;        // a pixel corner of the source (aligned only)
  double pixel_x_m = 0, pixel_y_m = 0;  // pixel size (aligned only)
  // The largest north-up box inside the DEM's footprint in the output CRS,
  // metres (pixel edges): a crop inside it has data everywhere.
  BoundingBox covered{0, 0, 0, 0};
};
Result<ImportGrid> import_grid(const std::string& path, const ImportOptions& options);

// The crop (pixel edges, output CRS metres) whose posts cover `area` grown by
// `margin_m` on every side, in whole pixels of `grid`. Refuses an area that is
// not a box (message names `option`), and one the DEM does not cover with its
// margin, naming each short side and by how many metres.
Result<BoundingBox> crop_for_area(const ImportGrid& grid, const BoundingBox& area, double margin_m,
                                  const std::string& option = "--area");

}  // namespace visvol::fields
