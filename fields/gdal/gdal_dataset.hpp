// Internal to fields/gdal: GDAL datasets as owned handles, and the steps
// shared by reading and importing a DEM.
#pragma once

#include <gdal_priv.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fields/gdal/dem_io.hpp"

namespace visvol::fields::gdal {

// Registers drivers once and routes GDAL's messages to CPLGetLastErrorMsg.
void register_gdal();
std::string last_gdal_error();

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

// Opens a raster read-only with at least one band (any raster driver, or only
// `drivers`). Missing files give the OS's reason.
Result<DatasetPtr> open_raster(const std::string& path, const std::vector<std::string>& drivers = {});

// The header of an opened raster; `name` names it in messages.
Result<DemInfo> info_of(GDALDataset& ds, const std::string& name);

// Metres per unit for a band unit string ("ft", "US survey foot", "m", ...;
// none is metres), or nothing for a unit it does not know.
std::optional<double> vertical_factor(std::string unit);

// Refuses a geotransform no DEM should have, naming what was found: a
// non-finite term, rotation or shear, a pixel width <= 0 or height >= 0 (not
// north-up: a negative ESRI cellsize flips the grid), pixels outside
// kMinPostSpacingM..kMaxPostSpacingM (kMinPixelDeg..kMaxPixelDeg when
// `geographic`), corners beyond kMaxCoordinateM (longitude +-360, latitude +-90).
Status check_geotransform(const DemInfo& info, const std::string& name, bool geographic);

// Refuses what the heightfield cannot hold: degrees, non-metre CRS units,
// rotated, flipped or non-square pixels, sizes beyond the limits.
Status check_metric_grid(const DemInfo& info, const std::string& name, std::size_t max_posts,
                         const std::string& max_posts_reason = "");

// Band 1 as a heightfield in metres (scale, offset and `vertical_to_m`
// applied), nodata refused or filled per `options`.
Result<Heightfield> to_heightfield(GDALDataset& ds, const DemInfo& info, const std::string& name,
                                   const DemReadOptions& options, double vertical_to_m);

// Band 1 as doubles.
Status read_band_values_double(GDALDataset& ds, const std::string& path, std::vector<double>& out);

}  // namespace visvol::fields::gdal
