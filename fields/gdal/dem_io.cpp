#include "fields/gdal/dem_io.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_alg.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cctype>
#include <cmath>
#include <memory>
#include <mutex>
#include <sstream>
#include <type_traits>

#include "rt/base/atomic_file.hpp"

namespace visvol::fields {

namespace {

void register_gdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    // Errors come back through CPLGetLastErrorMsg; keep stderr for our messages.
    CPLSetErrorHandler(CPLQuietErrorHandler);
  });
}

std::string last_gdal_error() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(msg) : std::string("no details from GDAL");
}

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

Result<DatasetPtr> open_raster(const std::string& path,
                               const std::vector<std::string>& drivers = {}) {
  register_gdal();
  // GDAL also opens /vsi paths and URLs-like names; only plain paths get the OS's reason.
  if (path.rfind("/vsi", 0) != 0 && ::access(path.c_str(), R_OK) != 0) {
    return io_error(path + ": " + std::strerror(errno));
  }
  CPLErrorReset();
  std::vector<const char*> allowed;
  for (const std::string& d : drivers) allowed.push_back(d.c_str());
  allowed.push_back(nullptr);
  GDALDataset* ds = GDALDataset::Open(path.c_str(),
                                      GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR,
                                      drivers.empty() ? nullptr : allowed.data());
  if (!ds) return io_error(path + ": cannot open as a raster: " + last_gdal_error());
  DatasetPtr owned(ds);
  if (ds->GetRasterCount() < 1) return invalid_argument(path + ": raster has no bands");
  return owned;
}

// Metres per unit for the vertical units GDAL reports.
double vertical_factor(std::string unit) {
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (unit == "ft" || unit == "foot" || unit == "feet" || unit == "international foot") return 0.3048;
  if (unit == "us-ft" || unit == "ftus" || unit == "us survey foot") return 1200.0 / 3937.0;
  return 1.0;
}

template <typename T>
Status read_band_values(GDALDataset& ds, const std::string& path, std::vector<T>& out) {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>);
  GDALRasterBand* band = ds.GetRasterBand(1);
  const int nx = ds.GetRasterXSize(), ny = ds.GetRasterYSize();
  out.resize(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  CPLErrorReset();
  const GDALDataType type = std::is_same_v<T, float> ? GDT_Float32 : GDT_Float64;
  if (band->RasterIO(GF_Read, 0, 0, nx, ny, out.data(), nx, ny, type, 0, 0) != CE_None) {
    return io_error(path + ": cannot read band 1: " + last_gdal_error());
  }
  return Status::ok_status();
}

}  // namespace

Result<DemInfo> read_dem_info(const std::string& path) { return read_dem_info(path, {}); }

Result<DemInfo> read_dem_info(const std::string& path, const std::vector<std::string>& drivers) {
  Result<DatasetPtr> opened = open_raster(path, drivers);
  if (!opened.ok()) return opened.status();
  GDALDataset& ds = **opened;
  DemInfo info;
  info.driver = ds.GetDriver() ? ds.GetDriver()->GetDescription() : "";
  info.nx = ds.GetRasterXSize();
  info.ny = ds.GetRasterYSize();
  if (ds.GetGeoTransform(info.geotransform) != CE_None) {
    return invalid_argument(path + ": has no georeference (geotransform); post spacing is unknown");
  }
  if (const OGRSpatialReference* srs = ds.GetSpatialRef()) {
    char* wkt = nullptr;
    const char* options[] = {"FORMAT=WKT2_2019", nullptr};
    if (srs->exportToWkt(&wkt, options) == OGRERR_NONE && wkt) info.crs_wkt = wkt;
    CPLFree(wkt);
    info.crs_name = srs->GetName() ? srs->GetName() : "";
    info.geographic = srs->IsGeographic();
    if (srs->IsProjected()) info.linear_unit_m = srs->GetLinearUnits();
  }
  GDALRasterBand* band = ds.GetRasterBand(1);
  info.vertical_unit = band->GetUnitType() ? band->GetUnitType() : "";
  info.vertical_to_m = vertical_factor(info.vertical_unit);
  int has = 0;
  info.nodata = band->GetNoDataValue(&has);
  info.has_nodata = has != 0;
  return info;
}

namespace {

// A raster with no CRS whose whole extent fits longitude and latitude and
// whose pixels are finer than 0.1 units is almost surely in degrees.
bool looks_like_degrees(const DemInfo& info) {
  if (!info.crs_wkt.empty()) return false;
  const double* gt = info.geotransform;
  const double x0 = gt[0], x1 = gt[0] + gt[1] * info.nx;
  const double y0 = gt[3], y1 = gt[3] + gt[5] * info.ny;
  auto within = [](double v, double limit) { return v >= -limit && v <= limit; };
  return std::fabs(gt[1]) < 0.1 && within(x0, 360) && within(x1, 360) && within(y0, 90) &&
         within(y1, 90);
}

constexpr int kMaxFillDistancePosts = 128;

// Fills nodata posts in `raw` (in place) with GDALFillNodata on an in-memory copy.
Status fill_nodata(const std::string& path, int nx, int ny, double nodata,
                   std::vector<float>& raw) {
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  if (!mem) return Status(Errc::unsupported, "GDAL has no MEM driver");
  DatasetPtr ds(mem->Create("", nx, ny, 1, GDT_Float32, nullptr));
  if (!ds) return io_error(path + ": cannot create a work raster: " + last_gdal_error());
  GDALRasterBand* band = ds->GetRasterBand(1);
  for (float& v : raw) {
    if (!std::isfinite(v)) v = static_cast<float>(nodata);
  }
  if (band->SetNoDataValue(nodata) != CE_None ||
      band->RasterIO(GF_Write, 0, 0, nx, ny, raw.data(), nx, ny, GDT_Float32, 0, 0) != CE_None) {
    return io_error(path + ": cannot stage nodata filling: " + last_gdal_error());
  }
  // Holes are filled from their edges up to this far; wider ones stay and are
  // reported (and a far search over a sparse raster would take hours).
  const double search = std::min(std::max(nx, ny), kMaxFillDistancePosts);
  if (GDALFillNodata(GDALRasterBand::ToHandle(band), nullptr, search, 0, 0, nullptr, nullptr,
                     nullptr) != CE_None ||
      band->RasterIO(GF_Read, 0, 0, nx, ny, raw.data(), nx, ny, GDT_Float32, 0, 0) != CE_None) {
    return io_error(path + ": filling nodata failed: " + last_gdal_error());
  }
  return Status::ok_status();
}

}  // namespace

Result<Heightfield> read_heightfield(const std::string& path, const DemReadOptions& options) {
  Result<DemInfo> info_r = read_dem_info(path, options.drivers);
  if (!info_r.ok()) return info_r.status();
  const DemInfo& info = *info_r;
  const double* gt = info.geotransform;
  std::ostringstream msg;
  if (info.geographic) {
    msg << path << ": CRS '" << info.crs_name
        << "' is geographic (degrees); project it to a metric CRS first "
           "(for example gdalwarp -t_srs EPSG:326<zone> -r bilinear)";
    return invalid_argument(msg.str());
  }
  if (looks_like_degrees(info)) {
    msg << path << ": has no CRS, and its extent and pixel size (" << gt[1]
        << ") look like degrees; assign its CRS first "
           "(for example gdal_translate -a_srs EPSG:4326) so it can be projected";
    return invalid_argument(msg.str());
  }
  if (std::fabs(info.linear_unit_m - 1.0) > 1e-9) {
    msg << path << ": CRS unit is " << info.linear_unit_m
        << " m, not metres; reproject to a metric CRS";
    return invalid_argument(msg.str());
  }
  if (gt[2] != 0 || gt[4] != 0) {
    msg << path << ": rotated geotransform; warp it north-up first (gdalwarp)";
    return invalid_argument(msg.str());
  }
  if (!(gt[1] > 0 && gt[5] < 0)) {
    msg << path << ": pixel size " << gt[1] << " x " << gt[5]
        << " is not north-up (x > 0, y < 0); warp it first (gdalwarp)";
    return invalid_argument(msg.str());
  }
  const double sx = gt[1], sy = -gt[5];
  if (std::fabs(sx - sy) > 1e-3 * std::max(sx, sy)) {
    msg << path << ": pixels are " << sx << " x " << sy
        << " m; resample to square pixels first (gdalwarp -tr S S)";
    return invalid_argument(msg.str());
  }
  if (info.nx > kMaxPostsPerSide || info.ny > kMaxPostsPerSide || info.nx < 2 || info.ny < 2) {
    msg << path << ": grid is " << info.nx << " x " << info.ny << " posts; supported sizes are 2.."
        << kMaxPostsPerSide << " a side";
    return invalid_argument(msg.str());
  }

  if (static_cast<std::size_t>(info.nx) * static_cast<std::size_t>(info.ny) > options.max_posts) {
    msg << path << ": " << info.nx << " x " << info.ny << " posts is more than the "
        << options.max_posts << " this read allows; crop or resample it";
    return invalid_argument(msg.str());
  }
  Result<DatasetPtr> opened = open_raster(path, options.drivers);
  if (!opened.ok()) return opened.status();
  std::vector<float> raw;
  VISVOL_RETURN_IF_ERROR(read_band_values(**opened, path, raw));
  GDALRasterBand* band = (*opened)->GetRasterBand(1);
  int has_scale = 0, has_offset = 0;
  const double scale = band->GetScale(&has_scale);
  const double offset = band->GetOffset(&has_offset);

  if (options.nodata == NodataPolicy::fill && info.has_nodata) {
    const float nd = static_cast<float>(info.nodata);
    const std::size_t holes = static_cast<std::size_t>(std::count_if(
        raw.begin(), raw.end(), [&](float v) { return !std::isfinite(v) || v == nd; }));
    if (holes * 2 > raw.size()) {
      msg << path << ": " << holes << " of " << raw.size()
          << " posts are nodata; too few to fill from, crop the DEM to its data";
      return invalid_argument(msg.str());
    }
    if (holes > 0) VISVOL_RETURN_IF_ERROR(fill_nodata(path, info.nx, info.ny, info.nodata, raw));
  }
  Heightfield hf;
  hf.nx = info.nx;
  hf.ny = info.ny;
  hf.spacing_m = std::sqrt(sx * sy);  // equal within 0.1%, checked above
  hf.origin_x = gt[0] + 0.5 * sx;     // pixel centre of the north-west pixel
  hf.origin_y = gt[3] - 0.5 * sy;
  hf.crs_wkt = info.crs_wkt;
  hf.height_m.resize(raw.size());
  std::size_t bad = 0, first_bad = 0;
  // Nodata compares in the type the band was read in.
  const float nodata = static_cast<float>(info.nodata);
  for (std::size_t n = 0; n < raw.size(); ++n) {
    const double v = raw[n];
    if (!std::isfinite(v) || (info.has_nodata && raw[n] == nodata)) {
      if (bad++ == 0) first_bad = n;
      continue;
    }
    const double metres = (v * (has_scale ? scale : 1.0) + (has_offset ? offset : 0.0)) * info.vertical_to_m;
    hf.height_m[n] = static_cast<float>(metres);
  }
  if (bad > 0) {
    msg << path << ": " << bad << " posts are nodata or NaN, the first at ("
        << first_bad % static_cast<std::size_t>(hf.nx) << ", "
        << first_bad / static_cast<std::size_t>(hf.nx) << ")"
        << (options.nodata == NodataPolicy::fill
                ? " and lie more than 128 posts from data, too far to fill; crop the DEM"
                : "; fill them or crop the DEM");
    return invalid_argument(msg.str());
  }
  VISVOL_RETURN_IF_ERROR(validate(hf, path));
  return hf;
}

Result<std::vector<float>> read_raster_like(const std::string& path, const Heightfield& like) {
  Result<DatasetPtr> opened = open_raster(path);
  if (!opened.ok()) return opened.status();
  GDALDataset& ds = **opened;
  if (ds.GetRasterXSize() != like.nx || ds.GetRasterYSize() != like.ny) {
    std::ostringstream msg;
    msg << path << ": grid is " << ds.GetRasterXSize() << " x " << ds.GetRasterYSize()
        << ", the terrain is " << like.nx << " x " << like.ny << "; they must match";
    return invalid_argument(msg.str());
  }
  std::vector<double> raw;
  VISVOL_RETURN_IF_ERROR(read_band_values(ds, path, raw));
  int has_nodata = 0;
  const double nodata = ds.GetRasterBand(1)->GetNoDataValue(&has_nodata);
  std::vector<float> out(raw.size());
  for (std::size_t n = 0; n < raw.size(); ++n) {
    if (!std::isfinite(raw[n]) || (has_nodata && raw[n] == nodata)) {
      std::ostringstream msg;
      msg << path << ": cell (" << n % static_cast<std::size_t>(like.nx) << ", "
          << n / static_cast<std::size_t>(like.nx) << ") is nodata or NaN";
      return invalid_argument(msg.str());
    }
    out[n] = static_cast<float>(raw[n]);
  }
  return out;
}

Result<RasterBand> read_band(const std::string& path) {
  Result<DatasetPtr> opened = open_raster(path);
  if (!opened.ok()) return opened.status();
  GDALDataset& ds = **opened;
  RasterBand band;
  band.nx = ds.GetRasterXSize();
  band.ny = ds.GetRasterYSize();
  VISVOL_RETURN_IF_ERROR(read_band_values(ds, path, band.value));
  int has_nodata = 0;
  const double nodata = ds.GetRasterBand(1)->GetNoDataValue(&has_nodata);
  band.valid.resize(band.value.size());
  for (std::size_t n = 0; n < band.value.size(); ++n) {
    const double v = band.value[n];
    band.valid[n] = std::isfinite(v) && !(has_nodata && v == nodata) ? 1 : 0;
  }
  return band;
}

std::string crs_name(const std::string& wkt) {
  if (wkt.empty()) return "local metres";
  OGRSpatialReference srs;
  if (srs.importFromWkt(wkt.c_str()) != OGRERR_NONE || !srs.GetName()) return "unnamed CRS";
  return srs.GetName();
}

namespace {

Status write_geotiff(const std::string& path, const Heightfield& like, GDALDataType type,
                     const void* values, double nodata) {
  register_gdal();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) return Status(Errc::unsupported, "GDAL has no GTiff driver");
  const std::string temp = temp_path_for(path);
  const char* options[] = {"COMPRESS=DEFLATE", "TILED=YES", nullptr};
  CPLErrorReset();
  GDALDataset* ds = driver->Create(temp.c_str(), like.nx, like.ny, 1, type,
                                   const_cast<char**>(options));
  if (!ds) return io_error(path + ": cannot create: " + last_gdal_error());
  double gt[6] = {like.origin_x - 0.5 * like.spacing_m, like.spacing_m, 0,
                  like.origin_y + 0.5 * like.spacing_m, 0, -like.spacing_m};
  bool ok = ds->SetGeoTransform(gt) == CE_None;
  if (!like.crs_wkt.empty()) ok = ok && ds->SetProjection(like.crs_wkt.c_str()) == CE_None;
  GDALRasterBand* band = ds->GetRasterBand(1);
  ok = ok && band->SetNoDataValue(nodata) == CE_None;
  ok = ok && band->RasterIO(GF_Write, 0, 0, like.nx, like.ny, const_cast<void*>(values), like.nx,
                            like.ny, type, 0, 0) == CE_None;
  const std::string detail = ok ? "" : last_gdal_error();
  // GDAL 3.6's GDALClose returns nothing: a failed flush shows as an error state.
  CPLErrorReset();
  GDALClose(GDALDataset::ToHandle(ds));
  if (CPLGetLastErrorType() == CE_Failure || CPLGetLastErrorType() == CE_Fatal) ok = false;
  if (!ok) {
    discard_file(temp);
    return io_error(path + ": cannot write GeoTIFF: " + (detail.empty() ? last_gdal_error() : detail));
  }
  return commit_file(temp, path);
}

}  // namespace

Status write_geotiff_u8(const std::string& path, const Heightfield& like,
                        const std::vector<std::uint8_t>& values, int nodata) {
  if (values.size() != like.size()) return invalid_argument(path + ": raster size mismatch");
  return write_geotiff(path, like, GDT_Byte, values.data(), nodata);
}

Status write_geotiff_f32(const std::string& path, const Heightfield& like,
                         const std::vector<float>& values, double nodata) {
  if (values.size() != like.size()) return invalid_argument(path + ": raster size mismatch");
  return write_geotiff(path, like, GDT_Float32, values.data(), nodata);
}

}  // namespace visvol::fields
