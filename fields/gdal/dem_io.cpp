#include "fields/gdal/dem_io.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_alg.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <sstream>
#include <type_traits>

#include "fields/gdal/ascii_grid.hpp"
#include "fields/gdal/gdal_dataset.hpp"
#include "io/atomic_file.hpp"
#include "io/input_file.hpp"

namespace visvol::fields {

namespace gdal {

void register_gdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    // Never write .aux.xml side files next to the user's data.
    CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");
    // nor the .properties file /vsigzip/ writes beside an archive it measured
    CPLSetConfigOption("CPL_VSIL_GZIP_WRITE_PROPERTIES", "NO");
    // Errors come back through CPLGetLastErrorMsg; keep stderr for our messages.
    CPLSetErrorHandler(CPLQuietErrorHandler);
  });
}

std::string last_gdal_error() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(msg) : std::string("no details from GDAL");
}

// GDAL's virtual file systems (/vsi...): an archive reader over a local file
// gets that file checked as any input (a FIFO or a device would block or
// worse inside GDAL's open); memory files (/vsimem/, the fuzzer's) touch no
// file; any other, the network ones above all (/vsicurl/, /vsis3/, ...), is
// refused: the tools read local files only.
Status check_virtual_path(const std::string& path) {
  if (path.size() > PATH_MAX) return invalid_argument(path.substr(0, 64) + "...: a path longer than PATH_MAX");
  if (path.rfind("/vsimem/", 0) == 0) return Status::ok_status();
  std::string rest;
  bool archive_reader = false;
  for (const char* archive : {"/vsizip/", "/vsigzip/", "/vsitar/"}) {
    if (path.rfind(archive, 0) != 0) continue;
    rest = path.substr(std::strlen(archive));
    archive_reader = true;
  }
  if (!archive_reader) {
    return invalid_argument(path +
                            ": not a GDAL file system visvol reads; a DEM is a local file, plain or in "
                            "a zip, gzip or tar archive (/vsizip/, /vsigzip/, /vsitar/)");
  }
  if (rest.empty()) return invalid_argument(path + ": names no archive");
  if (rest.rfind("/vsi", 0) == 0) return check_virtual_path(rest);  // an archive in an archive
  if (rest.front() == '{') {  // /vsizip/{ARCHIVE}/MEMBER, ARCHIVE itself braced or virtual
    std::size_t close = 0;
    for (int depth = 0; close < rest.size(); ++close) {
      depth += rest[close] == '{' ? 1 : rest[close] == '}' ? -1 : 0;
      if (depth == 0) break;
    }
    if (close == rest.size()) return invalid_argument(path + ": no '}' closes the archive's name");
    const std::string archive = rest.substr(1, close - 1);
    if (archive.rfind("/vsi", 0) == 0) return check_virtual_path(archive);
    VISVOL_RETURN_IF_ERROR(check_input_file(archive));
    return check_side_files(archive);
  }
  // The archive is the longest leading part that names something other than
  // a directory; the rest is the member inside it. None: GDAL says "cannot
  // open". The archive's side files (a grid's DEM.asc.prj beside DEM.asc.gz,
  // which GDAL looks for there) are checked as a plain DEM's.
  for (std::size_t end = rest.size(); end != std::string::npos && end > 0; end = rest.rfind('/', end - 1)) {
    const std::string archive = rest.substr(0, end);
    struct stat st {};
    if (::stat(archive.c_str(), &st) == 0 && !S_ISDIR(st.st_mode)) {
      VISVOL_RETURN_IF_ERROR(check_input_file(archive));
      return check_side_files(archive);
    }
  }
  return Status::ok_status();
}

Result<DatasetPtr> open_raster(const std::string& path, const std::vector<std::string>& drivers) {
  register_gdal();
  if (path.rfind("/vsi", 0) == 0) {
    VISVOL_RETURN_IF_ERROR(check_virtual_path(path));
  } else {  // only plain paths get the OS's reason, and side files to check
    VISVOL_RETURN_IF_ERROR(check_input_file(path));
    VISVOL_RETURN_IF_ERROR(check_side_files(path));
  }
  std::vector<const char*> allowed;
  allowed.reserve(drivers.size() + 1);
  for (const std::string& d : drivers) allowed.push_back(d.c_str());
  allowed.push_back(nullptr);
  CPLErrorReset();
  GDALDataset* ds = GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR,
                                      drivers.empty() ? nullptr : allowed.data());
  if (!ds) return io_error(path + ": cannot open as a raster: " + last_gdal_error());
  DatasetPtr owned(ds);
  if (ds->GetRasterCount() < 1) return invalid_argument(path + ": raster has no bands");
  const char* driver = ds->GetDriver() ? ds->GetDriver()->GetDescription() : "";
  if (is_ascii_grid_driver(driver)) {
    VISVOL_RETURN_IF_ERROR(check_ascii_grid_cells(path, ds->GetRasterXSize(), ds->GetRasterYSize()));
  }
  return owned;
}

std::optional<double> vertical_factor(std::string unit) {
  std::transform(unit.begin(), unit.end(), unit.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // Band units as GDAL's drivers spell them (GeoTIFF vertical units, USGS DEM, DTED, SRTM).
  for (const char* metre : {"", "m", "metre", "metres", "meter", "meters"}) {
    if (unit == metre) return 1.0;
  }
  for (const char* foot : {"ft", "foot", "feet", "international foot"}) {
    if (unit == foot) return 0.3048;
  }
  for (const char* us_foot : {"us-ft", "ftus", "us survey foot", "us_survey_foot", "foot_us"}) {
    if (unit == us_foot) return 1200.0 / 3937.0;
  }
  return std::nullopt;
}

Result<DemInfo> info_of(GDALDataset& ds, const std::string& name) {
  DemInfo info;
  info.driver = ds.GetDriver() ? ds.GetDriver()->GetDescription() : "";
  info.nx = ds.GetRasterXSize();
  info.ny = ds.GetRasterYSize();
  if (ds.GetGeoTransform(info.geotransform) != CE_None) {
    return invalid_argument(name + ": has no georeference (geotransform); post spacing is unknown");
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
  const std::optional<double> to_m = vertical_factor(info.vertical_unit);
  if (!to_m) {
    return invalid_argument(name + ": heights are in '" + info.vertical_unit +
                            "', a unit visvol does not know; known: metre (m, meters), foot (ft, feet), "
                            "US survey foot (us-ft); none means metres");
  }
  info.vertical_to_m = *to_m;
  int has = 0;
  info.nodata = band->GetNoDataValue(&has);
  info.has_nodata = has != 0;
  return info;
}

namespace {

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

// A raster with no CRS whose whole extent fits longitude and latitude and
// whose pixels are finer than 0.1 units is almost surely in degrees.
bool looks_like_degrees(const DemInfo& info) {
  if (!info.crs_wkt.empty()) return false;
  const double* gt = info.geotransform;
  const double x0 = gt[0], x1 = gt[0] + gt[1] * info.nx;
  const double y0 = gt[3], y1 = gt[3] + gt[5] * info.ny;
  auto within = [](double v, double limit) { return v >= -limit && v <= limit; };
  return std::fabs(gt[1]) < 0.1 && within(x0, 360) && within(x1, 360) && within(y0, 90) && within(y1, 90);
}

constexpr int kMaxFillDistancePosts = 128;

// Fills nodata posts in `raw` (in place) with GDALFillNodata on an in-memory copy.
Status fill_nodata(const std::string& path, int nx, int ny, double nodata, std::vector<float>& raw) {
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
  // Its work rasters stay in memory: nothing is written to the working directory.
  const char* fill_options[] = {"TEMP_FILE_DRIVER=MEM", nullptr};
  if (GDALFillNodata(GDALRasterBand::ToHandle(band), nullptr, search, 0, 0, const_cast<char**>(fill_options), nullptr,
                     nullptr) != CE_None ||
      band->RasterIO(GF_Read, 0, 0, nx, ny, raw.data(), nx, ny, GDT_Float32, 0, 0) != CE_None) {
    return io_error(path + ": filling nodata failed: " + last_gdal_error());
  }
  return Status::ok_status();
}

}  // namespace

namespace {

std::string geotransform_text(const double* gt) {
  std::ostringstream s;
  s.precision(10);
  s << "(" << gt[0] << ", " << gt[1] << ", " << gt[2] << ", " << gt[3] << ", " << gt[4] << ", " << gt[5] << ")";
  return s.str();
}

Status refuse_unlabelled_degrees(const DemInfo& info, const std::string& name) {
  if (!looks_like_degrees(info)) return Status::ok_status();
  std::ostringstream msg;
  msg << name << ": has no CRS, and its extent and pixel size (" << info.geotransform[1]
      << ") look like degrees; give its CRS (--assume-srs EPSG:4326) so it can be projected";
  return invalid_argument(msg.str());
}

// Pixel width and height inside the range for the CRS's unit.
Status check_pixel_size(const DemInfo& info, const std::string& name, bool geographic) {
  const double* gt = info.geotransform;
  std::ostringstream msg;
  msg.precision(10);
  msg << name << ": pixel size " << gt[1] << " x " << -gt[5];
  if (geographic) {
    if (gt[1] < kMinPixelDeg || gt[1] > kMaxPixelDeg || -gt[5] < kMinPixelDeg || -gt[5] > kMaxPixelDeg) {
      msg << " degrees is outside " << kMinPixelDeg << ".." << kMaxPixelDeg << " degrees";
      return invalid_argument(msg.str());
    }
    return Status::ok_status();
  }
  const double sx_m = gt[1] * info.linear_unit_m, sy_m = -gt[5] * info.linear_unit_m;
  if (sx_m < kMinPostSpacingM || sx_m > kMaxPostSpacingM || sy_m < kMinPostSpacingM || sy_m > kMaxPostSpacingM) {
    msg << (info.linear_unit_m == 1.0 ? " m" : " CRS units") << " is outside " << kMinPostSpacingM << ".."
        << kMaxPostSpacingM << " m";
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

// The raster's corners inside what the CRS can hold.
Status check_extent(const DemInfo& info, const std::string& name, bool geographic) {
  const double* gt = info.geotransform;
  const double x0 = gt[0], x1 = gt[0] + gt[1] * info.nx;
  const double y1 = gt[3], y0 = gt[3] + gt[5] * info.ny;
  std::ostringstream msg;
  msg.precision(10);
  msg << name << ": extent x " << x0 << ".." << x1 << ", y " << y0 << ".." << y1;
  if (geographic) {
    const double lat_slack_deg = -gt[5];  // pixel edges of a global grid may pass a pole by one pixel
    if (x0 < -360 || x1 > 360 || y0 < -90 - lat_slack_deg || y1 > 90 + lat_slack_deg) {
      msg << " degrees is not on Earth (longitude -360..360, latitude -90..90)";
      return invalid_argument(msg.str());
    }
    return Status::ok_status();
  }
  const double limit = kMaxCoordinateM / info.linear_unit_m;
  if (std::fabs(x0) > limit || std::fabs(x1) > limit || std::fabs(y0) > limit || std::fabs(y1) > limit) {
    msg << (info.linear_unit_m == 1.0 ? " m" : " CRS units") << " reaches beyond +-" << kMaxCoordinateM
        << " m, outside any projected CRS on Earth";
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

}  // namespace

Status check_geotransform(const DemInfo& info, const std::string& name, bool geographic) {
  const double* gt = info.geotransform;
  if (!std::all_of(gt, gt + 6, [](double v) { return std::isfinite(v); })) {
    return invalid_argument(name + ": geotransform " + geotransform_text(gt) + " has a term that is not finite");
  }
  if (gt[2] != 0 || gt[4] != 0) {
    return invalid_argument(name + ": geotransform " + geotransform_text(gt) +
                            " has rotation or shear terms (the 3rd and 5th); visvol reads north-up "
                            "rasters only: warp it north-up first (gdalwarp)");
  }
  if (!(gt[1] > 0 && gt[5] < 0)) {
    std::ostringstream msg;
    msg << name << ": pixel size " << gt[1] << " x " << gt[5]
        << " (geotransform terms 2 and 6) is not north-up: the width must be > 0 and the height < 0 "
           "(row 0 the northern edge); a negative or zero cell size is not a valid grid, and a "
           "south-up raster must be warped north-up first (gdalwarp)";
    return invalid_argument(msg.str());
  }
  // Degrees without a CRS would fail the metre ranges below; say what they are.
  if (!geographic) VISVOL_RETURN_IF_ERROR(refuse_unlabelled_degrees(info, name));
  VISVOL_RETURN_IF_ERROR(check_pixel_size(info, name, geographic));
  return check_extent(info, name, geographic);
}

Status check_metric_grid(const DemInfo& info, const std::string& name, std::size_t max_posts,
                         const std::string& max_posts_reason) {
  const double* gt = info.geotransform;
  std::ostringstream msg;
  msg << name << ": ";
  if (info.geographic) {
    msg << "CRS '" << info.crs_name
        << "' is geographic (degrees); import projects it (visvol build and info do, to its UTM "
           "zone or --t-srs), or project it first (gdalwarp -t_srs EPSG:326<zone>)";
    return invalid_argument(msg.str());
  }
  VISVOL_RETURN_IF_ERROR(refuse_unlabelled_degrees(info, name));
  if (std::fabs(info.linear_unit_m - 1.0) > 1e-9) {
    msg << "CRS unit is " << info.linear_unit_m << " m, not metres; reproject it (--t-srs)";
    return invalid_argument(msg.str());
  }
  VISVOL_RETURN_IF_ERROR(check_geotransform(info, name, false));
  const double sx = gt[1], sy = -gt[5];
  if (std::fabs(sx - sy) > 1e-3 * std::max(sx, sy)) {
    msg << "pixels are " << sx << " x " << sy << " m; resample to square pixels (--spacing)";
    return invalid_argument(msg.str());
  }
  if (info.nx > kMaxPostsPerSide || info.ny > kMaxPostsPerSide || info.nx < 2 || info.ny < 2) {
    msg << "grid is " << info.nx << " x " << info.ny << " posts; supported sizes are 2.." << kMaxPostsPerSide
        << " a side";
    return invalid_argument(msg.str());
  }
  if (static_cast<std::size_t>(info.nx) * static_cast<std::size_t>(info.ny) > max_posts) {
    msg << info.nx << " x " << info.ny << " posts is more than the " << max_posts << " this read allows"
        << (max_posts_reason.empty() ? "" : " (" + max_posts_reason + ")") << "; crop or resample it";
    return invalid_argument(msg.str());
  }
  return Status::ok_status();
}

Result<Heightfield> to_heightfield(GDALDataset& ds, const DemInfo& info, const std::string& name,
                                   const DemReadOptions& options, double vertical_to_m) {
  std::vector<float> raw;
  VISVOL_RETURN_IF_ERROR(read_band_values(ds, name, raw));
  GDALRasterBand* band = ds.GetRasterBand(1);
  int has_scale = 0, has_offset = 0;
  const double scale = band->GetScale(&has_scale);
  const double offset = band->GetOffset(&has_offset);
  std::ostringstream msg;
  // Nodata compares in the type the band was read in.
  const float nodata = static_cast<float>(info.nodata);
  auto is_hole = [&](float v) { return !std::isfinite(v) || (info.has_nodata && v == nodata); };
  if (options.nodata == NodataPolicy::fill) {
    const std::size_t holes = static_cast<std::size_t>(std::count_if(raw.begin(), raw.end(), is_hole));
    if (holes * 2 > raw.size()) {
      msg << name << ": " << holes << " of " << raw.size()
          << " posts are nodata; too few to fill from, crop the DEM to its data";
      return invalid_argument(msg.str());
    }
    if (holes > 0) {
      const double fill_value = info.has_nodata ? info.nodata : -3.0e38;
      VISVOL_RETURN_IF_ERROR(fill_nodata(name, info.nx, info.ny, fill_value, raw));
    }
  }
  const double* gt = info.geotransform;
  const double sx = gt[1], sy = -gt[5];
  Heightfield hf;
  hf.nx = info.nx;
  hf.ny = info.ny;
  hf.spacing_m = std::sqrt(sx * sy);  // equal within 0.1%, checked by check_metric_grid
  hf.origin_x = gt[0] + 0.5 * sx;     // pixel centre of the north-west pixel
  hf.origin_y = gt[3] - 0.5 * sy;
  hf.crs_wkt = info.crs_wkt;
  hf.height_m.resize(raw.size());
  std::size_t bad = 0, first_bad = 0;
  for (std::size_t n = 0; n < raw.size(); ++n) {
    if (is_hole(raw[n])) {
      if (bad++ == 0) first_bad = n;
      continue;
    }
    const double v = raw[n];
    const double metres = (v * (has_scale ? scale : 1.0) + (has_offset ? offset : 0.0)) * vertical_to_m;
    hf.height_m[n] = static_cast<float>(metres);
  }
  if (bad > 0) {
    msg << name << ": " << bad << " posts are nodata or NaN, the first at ("
        << first_bad % static_cast<std::size_t>(hf.nx) << ", " << first_bad / static_cast<std::size_t>(hf.nx) << ")"
        << (options.nodata == NodataPolicy::fill
                ? " and lie more than 128 posts from data, too far to fill; crop the DEM"
                : "; fill them (--fill-nodata) or crop the DEM");
    return invalid_argument(msg.str());
  }
  VISVOL_RETURN_IF_ERROR(validate(hf, name));
  return hf;
}

Status read_band_values_double(GDALDataset& ds, const std::string& path, std::vector<double>& out) {
  return read_band_values(ds, path, out);
}

}  // namespace gdal

using gdal::DatasetPtr;
using gdal::last_gdal_error;
using gdal::open_raster;
using gdal::register_gdal;

Result<DemInfo> read_dem_info(const std::string& path) { return read_dem_info(path, {}); }

Result<DemInfo> read_dem_info(const std::string& path, const std::vector<std::string>& drivers) {
  Result<DatasetPtr> opened = open_raster(path, drivers);
  if (!opened.ok()) return opened.status();
  return gdal::info_of(**opened, path);
}

Result<Heightfield> read_heightfield(const std::string& path, const DemReadOptions& options) {
  Result<DatasetPtr> opened = open_raster(path, options.drivers);
  if (!opened.ok()) return opened.status();
  Result<DemInfo> info = gdal::info_of(**opened, path);
  if (!info.ok()) return info.status();
  VISVOL_RETURN_IF_ERROR(gdal::check_metric_grid(*info, path, options.max_posts));
  return gdal::to_heightfield(**opened, *info, path, options, info->vertical_to_m);
}

Result<std::vector<float>> read_raster_like(const std::string& path, const Heightfield& like) {
  // the terrain formats only: a VRT or WMS file could name network or device sources
  Result<DatasetPtr> opened = open_raster(path, dem_drivers());
  if (!opened.ok()) return opened.status();
  GDALDataset& ds = **opened;
  if (ds.GetRasterXSize() != like.nx || ds.GetRasterYSize() != like.ny) {
    std::ostringstream msg;
    msg << path << ": grid is " << ds.GetRasterXSize() << " x " << ds.GetRasterYSize() << ", the terrain is " << like.nx
        << " x " << like.ny << "; they must match";
    return invalid_argument(msg.str());
  }
  std::vector<double> raw;
  VISVOL_RETURN_IF_ERROR(gdal::read_band_values_double(ds, path, raw));
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
  Result<DatasetPtr> opened = open_raster(path, dem_drivers());
  if (!opened.ok()) return opened.status();
  GDALDataset& ds = **opened;
  RasterBand band;
  band.nx = ds.GetRasterXSize();
  band.ny = ds.GetRasterYSize();
  VISVOL_RETURN_IF_ERROR(gdal::read_band_values_double(ds, path, band.value));
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

Status write_geotiff(const std::string& path, const Heightfield& like, GDALDataType type, const void* values,
                     double nodata) {
  register_gdal();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) return Status(Errc::unsupported, "GDAL has no GTiff driver");
  // GDAL creates the file by name: inside a private directory of our own,
  // so no link planted next to the output can redirect it
  Result<OutputFile> out = OutputFile::create_for_library(path);
  if (!out.ok()) return out.status();
  const char* options[] = {"COMPRESS=DEFLATE", "TILED=YES", nullptr};
  CPLErrorReset();
  GDALDataset* ds = driver->Create(out->write_path().c_str(), like.nx, like.ny, 1, type, const_cast<char**>(options));
  if (!ds) return output_error(path + ": cannot create: " + last_gdal_error());
  double gt[6] = {like.origin_x - 0.5 * like.spacing_m,
                  like.spacing_m,
                  0,
                  like.origin_y + 0.5 * like.spacing_m,
                  0,
                  -like.spacing_m};
  bool ok = ds->SetGeoTransform(gt) == CE_None;
  if (!like.crs_wkt.empty()) ok = ok && ds->SetProjection(like.crs_wkt.c_str()) == CE_None;
  GDALRasterBand* band = ds->GetRasterBand(1);
  ok = ok && band->SetNoDataValue(nodata) == CE_None;
  ok = ok && band->RasterIO(GF_Write, 0, 0, like.nx, like.ny, const_cast<void*>(values), like.nx, like.ny, type, 0,
                            0) == CE_None;
  const std::string detail = ok ? "" : last_gdal_error();
  // GDAL 3.6's GDALClose returns nothing: a failed flush shows as an error state.
  CPLErrorReset();
  GDALClose(GDALDataset::ToHandle(ds));
  if (CPLGetLastErrorType() == CE_Failure || CPLGetLastErrorType() == CE_Fatal) ok = false;
  if (!ok) return output_error(path + ": cannot write GeoTIFF: " + (detail.empty() ? last_gdal_error() : detail));
  return out->commit();
}

}  // namespace

Status write_geotiff_u8(const std::string& path, const Heightfield& like, const std::vector<std::uint8_t>& values,
                        int nodata) {
  if (values.size() != like.size()) return invalid_argument(path + ": raster size mismatch");
  return write_geotiff(path, like, GDT_Byte, values.data(), nodata);
}

Status write_geotiff_f32(const std::string& path, const Heightfield& like, const std::vector<float>& values,
                         double nodata) {
  if (values.size() != like.size()) return invalid_argument(path + ": raster size mismatch");
  return write_geotiff(path, like, GDT_Float32, values.data(), nodata);
}

}  // namespace visvol::fields
