#include "fields/gdal/dem_import.hpp"

#include <gdal_utils.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "fields/gdal/gdal_dataset.hpp"

namespace visvol::fields {

namespace {

using gdal::DatasetPtr;

// Options for the GDAL utilities as argv, kept alive with their strings.
class Args {
 public:
  Args& add(const std::string& a) {
    strings_.push_back(a);
    return *this;
  }
  char** argv() {
    ptrs_.clear();
    for (std::string& s : strings_) ptrs_.push_back(s.data());
    ptrs_.push_back(nullptr);
    return ptrs_.data();
  }

 private:
  std::vector<std::string> strings_;
  std::vector<char*> ptrs_;
};

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

Result<OGRSpatialReference> parse_srs(const std::string& text, const std::string& what) {
  OGRSpatialReference srs;
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (srs.SetFromUserInput(text.c_str()) != OGRERR_NONE) {
    return invalid_argument(what + " '" + text + "' is not a CRS GDAL knows (try EPSG:<code>)");
  }
  return srs;
}

// Longitude and latitude of the raster's centre.
Result<std::pair<double, double>> centre_lon_lat(const DemInfo& info, const OGRSpatialReference& srs) {
  const double* gt = info.geotransform;
  double x = gt[0] + gt[1] * info.nx * 0.5 + gt[2] * info.ny * 0.5;
  double y = gt[3] + gt[4] * info.nx * 0.5 + gt[5] * info.ny * 0.5;
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReference source = srs;
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> ct(OGRCreateCoordinateTransformation(&source, &wgs84));
  if (!ct || !ct->Transform(1, &x, &y)) {
    return invalid_argument("cannot find the longitude and latitude of the DEM's centre");
  }
  return std::make_pair(x, y);
}

Result<DatasetPtr> run_warp(GDALDataset& src, Args& args, const std::string& name) {
  GDALWarpAppOptions* opts = GDALWarpAppOptionsNew(args.argv(), nullptr);
  if (!opts) return invalid_argument(name + ": invalid warp options: " + gdal::last_gdal_error());
  GDALDatasetH src_h = GDALDataset::ToHandle(&src);
  int usage_error = 0;
  CPLErrorReset();
  GDALDatasetH out = GDALWarp("", nullptr, 1, &src_h, opts, &usage_error);
  GDALWarpAppOptionsFree(opts);
  if (!out) return io_error(name + ": reprojection failed: " + gdal::last_gdal_error());
  return DatasetPtr(GDALDataset::FromHandle(out));
}

Result<DatasetPtr> run_translate(GDALDataset& src, Args& args, const std::string& name) {
  GDALTranslateOptions* opts = GDALTranslateOptionsNew(args.argv(), nullptr);
  if (!opts) return invalid_argument(name + ": invalid crop options: " + gdal::last_gdal_error());
  int usage_error = 0;
  CPLErrorReset();
  GDALDatasetH out = GDALTranslate("", GDALDataset::ToHandle(&src), opts, &usage_error);
  GDALTranslateOptionsFree(opts);
  if (!out) return io_error(name + ": crop failed: " + gdal::last_gdal_error());
  return DatasetPtr(GDALDataset::FromHandle(out));
}

}  // namespace

Status validate(const ImportOptions& o) {
  if (!(o.spacing_m >= 0) || !std::isfinite(o.spacing_m) || o.spacing_m > 1.0e5) {
    return invalid_argument("spacing: " + number(o.spacing_m) + " m is outside 0..100000 m");
  }
  if (o.crop) {
    const BoundingBox& b = *o.crop;
    if (!(std::isfinite(b.xmin) && std::isfinite(b.ymin) && std::isfinite(b.xmax) &&
          std::isfinite(b.ymax)) || !(b.xmax > b.xmin && b.ymax > b.ymin)) {
      return invalid_argument("crop: (" + number(b.xmin) + ", " + number(b.ymin) + ", " + number(b.xmax) +
                              ", " + number(b.ymax) + ") is not a box xmin ymin xmax ymax");
    }
  }
  for (const char* r : {"near", "bilinear", "cubic", "cubicspline", "lanczos", "average"}) {
    if (o.resampling == r) return Status::ok_status();
  }
  return invalid_argument("resampling: '" + o.resampling +
                          "' is not one of near, bilinear, cubic, cubicspline, lanczos, average");
}

std::string utm_srs_for(double lon_deg, double lat_deg) {
  const int zone = std::clamp(static_cast<int>(std::floor((lon_deg + 180.0) / 6.0)) + 1, 1, 60);
  return "EPSG:" + std::to_string((lat_deg >= 0 ? 32600 : 32700) + zone);
}

Result<Heightfield> import_dem(const std::string& path, const ImportOptions& options,
                               ImportReport* report) {
  VISVOL_RETURN_IF_ERROR(validate(options));
  Result<DatasetPtr> opened = gdal::open_raster(path, dem_drivers());
  if (!opened.ok()) return opened.status();
  GDALDataset& src = **opened;
  Result<DemInfo> info = gdal::info_of(src, path);
  if (!info.ok()) return info.status();
  ImportReport rep;
  rep.source = *info;
  std::ostringstream steps;

  // The source CRS: the file's own, or the one the user says it has.
  OGRSpatialReference source_srs;
  source_srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  bool has_srs = false;
  DatasetPtr assumed;  // a VRT over `src` with the assumed CRS (src stays open under it)
  if (!info->crs_wkt.empty()) {
    has_srs = source_srs.importFromWkt(info->crs_wkt.c_str()) == OGRERR_NONE;
  }
  if (!options.assume_srs.empty()) {
    if (has_srs) {
      return invalid_argument(path + ": has a CRS already ('" + info->crs_name +
                              "'); --assume-srs is for files without one");
    }
    Result<OGRSpatialReference> a = parse_srs(options.assume_srs, "--assume-srs");
    if (!a.ok()) return a.status();
    source_srs = *a;
    has_srs = true;
    // An in-memory VRT carries the assumed CRS; the user's file is never touched.
    Args a_args;
    a_args.add("-of").add("VRT").add("-a_srs").add(options.assume_srs);
    Result<DatasetPtr> vrt = run_translate(src, a_args, path);
    if (!vrt.ok()) return vrt.status();
    assumed = std::move(*vrt);
    steps << "assumed CRS " << source_srs.GetName() << "; ";
  }
  GDALDataset& in = assumed ? *assumed : src;
  const bool geographic = has_srs && source_srs.IsGeographic();

  // The output CRS.
  std::string target = options.target_srs;
  if (target.empty() && geographic) {
    Result<std::pair<double, double>> c = centre_lon_lat(*info, source_srs);
    if (!c.ok()) return c.status().with_context(path);
    target = utm_srs_for(c->first, c->second);
  }
  if (!target.empty() && !has_srs) {
    return invalid_argument(path + ": has no CRS, so it cannot be reprojected; give its CRS with --assume-srs");
  }
  if (!target.empty()) {
    Result<OGRSpatialReference> t = parse_srs(target, "--t-srs");
    if (!t.ok()) return t.status();
    if (!t->IsProjected()) return invalid_argument("--t-srs '" + target + "' is not a projected CRS");
    if (std::fabs(t->GetLinearUnits() - 1.0) > 1e-9) {
      return invalid_argument("--t-srs '" + target + "' is not in metres");
    }
    if (t->IsSame(&source_srs)) target.clear();  // nothing to project
  }

  const double* gt = info->geotransform;
  const bool square = std::fabs(std::fabs(gt[1]) - std::fabs(gt[5])) <= 1e-3 * std::fabs(gt[1]) &&
                      gt[2] == 0 && gt[4] == 0 && gt[1] > 0 && gt[5] < 0;
  const bool resample = options.spacing_m > 0 || (!square && !geographic);
  const bool warp = !target.empty() || resample;
  double spacing = options.spacing_m;
  if (!square && spacing == 0 && target.empty() && !geographic) {
    spacing = std::sqrt(std::fabs(gt[1] * gt[5]));  // square pixels of the same area
  }

  DatasetPtr result;
  if (warp) {
    Args args;
    args.add("-of").add("MEM").add("-r").add(options.resampling);
    if (!target.empty()) args.add("-t_srs").add(target);
    if (spacing > 0) args.add("-tr").add(number(spacing)).add(number(spacing));
    if (options.crop) {
      const BoundingBox& b = *options.crop;
      args.add("-te").add(number(b.xmin)).add(number(b.ymin)).add(number(b.xmax)).add(number(b.ymax));
    }
    if (info->has_nodata) args.add("-srcnodata").add(number(info->nodata));
    // Cells the source does not cover are nodata, never zeros.
    args.add("-dstnodata").add(info->has_nodata ? number(info->nodata) : "-3.0e38");
    args.add("-ot").add("Float32");
    Result<DatasetPtr> w = run_warp(in, args, path);
    if (!w.ok()) return w.status();
    result = std::move(*w);
    rep.warped = true;
    rep.cropped = options.crop.has_value();
    if (!target.empty()) steps << "projected to " << target << "; ";
    if (spacing > 0) steps << "resampled to " << number(spacing) << " m (" << options.resampling << "); ";
  } else if (options.crop) {
    const BoundingBox& b = *options.crop;
    Args args;
    args.add("-of").add("MEM").add("-projwin").add(number(b.xmin)).add(number(b.ymax)).add(number(b.xmax)).add(number(b.ymin));
    Result<DatasetPtr> t = run_translate(in, args, path);
    if (!t.ok()) return t.status();
    result = std::move(*t);
    rep.cropped = true;
  }
  if (rep.cropped) {
    steps << "cropped to " << number(options.crop->xmin) << " " << number(options.crop->ymin) << " "
          << number(options.crop->xmax) << " " << number(options.crop->ymax) << "; ";
  }
  GDALDataset& out = result ? *result : in;
  Result<DemInfo> out_info = gdal::info_of(out, path);
  if (!out_info.ok()) return out_info.status();
  if (result) {
    // Warping and cropping can drop the band's unit and nodata; keep the source's.
    out_info->vertical_unit = info->vertical_unit;
    if (!out_info->has_nodata && info->has_nodata) {
      out_info->has_nodata = true;
      out_info->nodata = info->nodata;
    }
    if (warp) {
      out_info->has_nodata = true;
      out_info->nodata = info->has_nodata ? info->nodata : -3.0e38;
    }
  }
  VISVOL_RETURN_IF_ERROR(gdal::check_metric_grid(*out_info, path, options.max_posts));
  DemReadOptions read;
  read.nodata = options.nodata;
  read.max_posts = options.max_posts;
  Result<Heightfield> hf = gdal::to_heightfield(out, *out_info, path, read, info->vertical_to_m);
  if (!hf.ok()) return hf.status();
  if (info->vertical_to_m != 1.0) steps << "heights from " << info->vertical_unit << " to metres; ";
  rep.output_crs = crs_name(hf->crs_wkt);
  rep.steps = steps.str();
  if (!rep.steps.empty()) rep.steps.resize(rep.steps.size() - 2);  // trailing "; "
  if (report) *report = rep;
  return hf;
}

}  // namespace visvol::fields
