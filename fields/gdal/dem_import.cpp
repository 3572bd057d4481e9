#include "fields/gdal/dem_import.hpp"

#include <gdal_alg.h>
#include <gdal_utils.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
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
  // the limited forms: no URL fetched, no file read (EPSG:, WKT, PROJ strings)
  if (srs.SetFromUserInput(text.c_str(), OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) != OGRERR_NONE) {
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

// What import does to a DEM, decided from its header and the options alone.
struct ImportPlan {
  DemInfo info;                    // the file as it is
  OGRSpatialReference source_srs;  // valid when has_srs
  bool has_srs = false;
  DatasetPtr assumed;    // a VRT over the file with the assumed CRS, or none
  std::string target;    // CRS to project to; empty: keep the source's
  bool warp = false;     // reproject or resample
  double spacing_m = 0;  // -tr of the warp; 0: GDAL's choice
  std::string steps;     // what was decided, for people ("assumed CRS ...; ")
};

// The source CRS: the file's own, or the one the user says it has (carried by
// an in-memory VRT; the user's file is never touched).
Status plan_source_srs(GDALDataset& src, const std::string& path, const ImportOptions& options, ImportPlan& plan) {
  plan.source_srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  if (!plan.info.crs_wkt.empty()) {
    plan.has_srs = plan.source_srs.importFromWkt(plan.info.crs_wkt.c_str()) == OGRERR_NONE;
  }
  if (options.assume_srs.empty()) return Status::ok_status();
  if (plan.has_srs) {
    return invalid_argument(path + ": has a CRS already ('" + plan.info.crs_name +
                            "'); --assume-srs is for files without one");
  }
  Result<OGRSpatialReference> a = parse_srs(options.assume_srs, "--assume-srs");
  if (!a.ok()) return a.status();
  plan.source_srs = *a;
  plan.has_srs = true;
  Args a_args;
  // the text passed the limited parse above: no URL or file name reaches GDAL's utilities
  a_args.add("-of").add("VRT").add("-a_srs").add(options.assume_srs);
  Result<DatasetPtr> vrt = run_translate(src, a_args, path);
  if (!vrt.ok()) return vrt.status();
  plan.assumed = std::move(*vrt);
  plan.steps += std::string("assumed CRS ") + plan.source_srs.GetName() + "; ";
  return Status::ok_status();
}

// The output CRS: the user's, or the UTM zone of the centre for a geographic
// DEM; empty when it is the source's own.
Status plan_target(const std::string& path, const ImportOptions& options, ImportPlan& plan) {
  const bool geographic = plan.has_srs && plan.source_srs.IsGeographic();
  std::string target = options.target_srs;
  if (target.empty() && geographic) {
    Result<std::pair<double, double>> c = centre_lon_lat(plan.info, plan.source_srs);
    if (!c.ok()) return c.status().with_context(path);
    target = utm_srs_for(c->first, c->second);
  }
  if (!target.empty() && !plan.has_srs) {
    return invalid_argument(path + ": has no CRS, so it cannot be reprojected; give its CRS with --assume-srs");
  }
  if (!target.empty()) {
    Result<OGRSpatialReference> t = parse_srs(target, "--t-srs");
    if (!t.ok()) return t.status();
    if (!t->IsProjected()) return invalid_argument("--t-srs '" + target + "' is not a projected CRS");
    if (std::fabs(t->GetLinearUnits() - 1.0) > 1e-9) {
      return invalid_argument("--t-srs '" + target + "' is not in metres");
    }
    if (t->IsSame(&plan.source_srs)) target.clear();  // nothing to project
  }
  plan.target = target;
  return Status::ok_status();
}

// Finite numbers with xmin < xmax and ymin < ymax.
bool is_box(const BoundingBox& b) {
  return std::isfinite(b.xmin) && std::isfinite(b.ymin) && std::isfinite(b.xmax) && std::isfinite(b.ymax) &&
         b.xmax > b.xmin && b.ymax > b.ymin;
}
std::string not_a_box(const BoundingBox& b) {
  return "(" + number(b.xmin) + ", " + number(b.ymin) + ", " + number(b.xmax) + ", " + number(b.ymax) +
         ") is not a box xmin ymin xmax ymax of finite numbers";
}

Result<ImportPlan> plan_import(GDALDataset& src, const std::string& path, const ImportOptions& options) {
  ImportPlan plan;
  Result<DemInfo> info = gdal::info_of(src, path);
  if (!info.ok()) return info.status();
  plan.info = *info;
  VISVOL_RETURN_IF_ERROR(plan_source_srs(src, path, options, plan));
  const bool geographic = plan.has_srs && plan.source_srs.IsGeographic();
  // A flipped, rotated or absurd grid is refused, not warped into something plausible.
  VISVOL_RETURN_IF_ERROR(gdal::check_geotransform(plan.info, path, geographic));
  VISVOL_RETURN_IF_ERROR(plan_target(path, options, plan));
  // Non-square pixels of a projected DEM become square ones of the same area.
  const double* gt = plan.info.geotransform;
  const bool square = std::fabs(std::fabs(gt[1]) - std::fabs(gt[5])) <= 1e-3 * std::fabs(gt[1]) && gt[2] == 0 &&
                      gt[4] == 0 && gt[1] > 0 && gt[5] < 0;
  const bool resample = options.spacing_m > 0 || (!square && !geographic);
  plan.warp = !plan.target.empty() || resample;
  plan.spacing_m = options.spacing_m;
  if (!square && plan.spacing_m == 0 && plan.target.empty() && !geographic) {
    plan.spacing_m = std::sqrt(std::fabs(gt[1] * gt[5]));
  }
  return plan;
}

// The grid of a DEM that import keeps on its own pixels.
ImportGrid aligned_grid(const DemInfo& info) {
  const double* gt = info.geotransform;
  ImportGrid g;
  g.aligned = true;
  g.spacing_m = std::sqrt(std::fabs(gt[1] * gt[5]));  // as the heightfield's (dem_io.cpp)
  g.edge_x = gt[0];
  g.edge_y = gt[3];
  g.pixel_x_m = gt[1];
  g.pixel_y_m = -gt[5];
  g.covered = {gt[0], gt[3] + info.ny * gt[5], gt[0] + info.nx * gt[1], gt[3]};
  return g;
}

struct TransformerCloser {
  void operator()(void* t) const { GDALDestroyGenImgProjTransformer(t); }
};
using TransformerPtr = std::unique_ptr<void, TransformerCloser>;

// The largest north-up box inside the footprint of a raster's pixels in the
// transformer's output: the innermost point of each edge, its edges sampled.
Result<BoundingBox> inner_footprint(void* transformer, int nx, int ny, const std::string& path) {
  constexpr int kSteps = 32;  // samples per edge, less one
  std::vector<double> x, y, z;
  for (int n = 0; n <= kSteps; ++n) {
    const double f = static_cast<double>(n) / kSteps;
    for (const auto& [px, py] :
         {std::pair{0.0, f * ny}, std::pair{1.0 * nx, f * ny}, std::pair{f * nx, 0.0}, std::pair{f * nx, 1.0 * ny}}) {
      x.push_back(px);
      y.push_back(py);
      z.push_back(0.0);
    }
  }
  std::vector<int> ok(x.size(), 0);
  GDALGenImgProjTransform(transformer, FALSE, static_cast<int>(x.size()), x.data(), y.data(), z.data(), ok.data());
  BoundingBox b{-HUGE_VAL, -HUGE_VAL, HUGE_VAL, HUGE_VAL};
  for (std::size_t n = 0; n < x.size(); ++n) {
    if (!ok[n]) return io_error(path + ": an edge of the DEM does not transform to the output CRS");
    switch (n % 4) {
      case 0: b.xmin = std::max(b.xmin, x[n]); break;   // west edge
      case 1: b.xmax = std::min(b.xmax, x[n]); break;   // east edge
      case 2: b.ymax = std::min(b.ymax, y[n]); break;   // north edge
      default: b.ymin = std::max(b.ymin, y[n]); break;  // south edge
    }
  }
  return b;
}

// GDAL's suggested output of a warp to the plan's CRS (what gdalwarp chooses),
// with the transformer that found it.
struct SuggestedWarp {
  double gt[6] = {0, 1, 0, 0, 0, -1};
  double extent[4] = {0, 0, 0, 0};  // xmin ymin xmax ymax, output CRS
  TransformerPtr transformer;
};

Result<SuggestedWarp> suggest_warp(GDALDataset& in, const ImportPlan& plan, const std::string& path) {
  CPLStringList transformer_options;
  if (!plan.target.empty()) {
    Result<OGRSpatialReference> t = parse_srs(plan.target, "--t-srs");
    if (!t.ok()) return t.status();
    char* wkt = nullptr;
    t->exportToWkt(&wkt);
    transformer_options.SetNameValue("DST_SRS", wkt);
    CPLFree(wkt);
  }
  CPLErrorReset();
  SuggestedWarp w;
  w.transformer.reset(
      GDALCreateGenImgProjTransformer2(GDALDataset::ToHandle(&in), nullptr, transformer_options.List()));
  if (!w.transformer) return io_error(path + ": cannot transform to the output CRS: " + gdal::last_gdal_error());
  int nx = 0, ny = 0;
  if (GDALSuggestedWarpOutput2(GDALDataset::ToHandle(&in), GDALGenImgProjTransform, w.transformer.get(), w.gt, &nx, &ny,
                               w.extent, 0) != CE_None) {
    return io_error(path + ": cannot find the output grid: " + gdal::last_gdal_error());
  }
  return w;
}

// The grid of a DEM that import warps: GDAL's suggested output unless a
// spacing is given.
Result<ImportGrid> warped_grid(GDALDataset& in, const ImportPlan& plan, const std::string& path) {
  Result<SuggestedWarp> w = suggest_warp(in, plan, path);
  if (!w.ok()) return w.status();
  ImportGrid g;
  g.spacing_m = plan.spacing_m > 0 ? plan.spacing_m : w->gt[1];
  Result<BoundingBox> covered = inner_footprint(w->transformer.get(), plan.info.nx, plan.info.ny, path);
  if (!covered.ok()) return covered.status();
  g.covered = *covered;
  return g;
}

// Refuses a warp whose output would exceed the size limits, before GDAL
// allocates and fills it (posts a side as gdalwarp rounds them).
Status check_warp_size(GDALDataset& in, const ImportPlan& plan, const ImportOptions& options, const std::string& path) {
  Result<SuggestedWarp> w = suggest_warp(in, plan, path);
  if (!w.ok()) return w.status();
  const double spacing_m = plan.spacing_m > 0 ? plan.spacing_m : w->gt[1];
  const BoundingBox box =
      options.crop ? *options.crop : BoundingBox{w->extent[0], w->extent[1], w->extent[2], w->extent[3]};
  const double nx = std::floor((box.xmax - box.xmin) / spacing_m + 0.5);
  const double ny = std::floor((box.ymax - box.ymin) / spacing_m + 0.5);
  if (std::isfinite(nx) && std::isfinite(ny) && nx <= kMaxPostsPerSide && ny <= kMaxPostsPerSide &&
      nx * ny <= static_cast<double>(options.max_posts)) {
    return Status::ok_status();
  }
  std::ostringstream msg;
  msg << path << ": the import would be " << nx << " x " << ny << " posts at " << number(spacing_m)
      << " m spacing; at most " << kMaxPostsPerSide << " a side and " << options.max_posts << " in all are supported"
      << (options.max_posts_reason.empty() ? "" : " (" + options.max_posts_reason + ")")
      << ": give a coarser --spacing or a smaller --crop";
  return invalid_argument(msg.str());
}

BoundingBox grown(const BoundingBox& b, double by_m) {
  return {b.xmin - by_m, b.ymin - by_m, b.xmax + by_m, b.ymax + by_m};
}

// `b` grown outward to the source's pixel edges.
BoundingBox snap_to_pixels(const ImportGrid& g, const BoundingBox& b) {
  return {g.edge_x + std::floor((b.xmin - g.edge_x) / g.pixel_x_m) * g.pixel_x_m,
          g.edge_y - std::ceil((g.edge_y - b.ymin) / g.pixel_y_m) * g.pixel_y_m,
          g.edge_x + std::ceil((b.xmax - g.edge_x) / g.pixel_x_m) * g.pixel_x_m,
          g.edge_y - std::floor((g.edge_y - b.ymax) / g.pixel_y_m) * g.pixel_y_m};
}

// `b` grown about its centre to whole posts a side.
BoundingBox whole_posts(const BoundingBox& b, double spacing_m) {
  const double wx = std::ceil((b.xmax - b.xmin) / spacing_m) * spacing_m;
  const double wy = std::ceil((b.ymax - b.ymin) / spacing_m) * spacing_m;
  const double cx = 0.5 * (b.xmin + b.xmax), cy = 0.5 * (b.ymin + b.ymax);
  return {cx - 0.5 * wx, cy - 0.5 * wy, cx + 0.5 * wx, cy + 0.5 * wy};
}

// Each side of `need` that `covered` does not reach, and by how much.
Status check_covered(const BoundingBox& covered, const BoundingBox& need, const BoundingBox& area, double margin_m,
                     const std::string& option) {
  const double tolerance_m = 1e-6;
  const struct {
    const char* side;
    double short_m;
  } sides[] = {{"west", covered.xmin - need.xmin},
               {"east", need.xmax - covered.xmax},
               {"south", covered.ymin - need.ymin},
               {"north", need.ymax - covered.ymax}};
  std::ostringstream shortfall;
  for (const auto& s : sides) {
    if (s.short_m <= tolerance_m) continue;
    shortfall << (shortfall.tellp() > 0 ? ", " : "") << std::fixed << std::setprecision(1) << s.short_m
              << " m short on the " << s.side << " side";
  }
  if (shortfall.tellp() == 0) return Status::ok_status();
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << option << " " << area.xmin << " " << area.ymin << " " << area.xmax << " "
      << area.ymax << " with its planning margin of " << margin_m << " m needs the DEM over x " << need.xmin << ".."
      << need.xmax << ", y " << need.ymin << ".." << need.ymax << " (pixel edges); it covers x " << covered.xmin << ".."
      << covered.xmax << ", y " << covered.ymin << ".." << covered.ymax << ": " << shortfall.str();
  return invalid_argument(msg.str());
}

}  // namespace

Status validate(const ImportOptions& o) {
  const bool keep = o.spacing_m == 0;
  if (!keep && !(o.spacing_m >= kMinPostSpacingM && o.spacing_m <= kMaxPostSpacingM)) {
    return invalid_argument("spacing: " + number(o.spacing_m) + " m is neither 0 (keep) nor in " +
                            number(kMinPostSpacingM) + ".." + number(kMaxPostSpacingM) + " m");
  }
  if (o.crop && !is_box(*o.crop)) return invalid_argument("crop: " + not_a_box(*o.crop));
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

Result<Heightfield> import_dem(const std::string& path, const ImportOptions& options, ImportReport* report) {
  VISVOL_RETURN_IF_ERROR(validate(options));
  Result<DatasetPtr> opened = gdal::open_raster(path, dem_drivers());
  if (!opened.ok()) return opened.status();
  GDALDataset& src = **opened;
  Result<ImportPlan> plan = plan_import(src, path, options);
  if (!plan.ok()) return plan.status();
  const DemInfo& info = plan->info;
  ImportReport rep;
  rep.source = info;
  std::ostringstream steps;
  steps << plan->steps;
  GDALDataset& in = plan->assumed ? *plan->assumed : src;
  const std::string& target = plan->target;
  const bool warp = plan->warp;
  const double spacing = plan->spacing_m;

  DatasetPtr result;
  if (warp) VISVOL_RETURN_IF_ERROR(check_warp_size(in, *plan, options, path));
  if (warp) {
    Args args;
    args.add("-of").add("MEM").add("-r").add(options.resampling);
    if (!target.empty()) args.add("-t_srs").add(target);
    if (spacing > 0) args.add("-tr").add(number(spacing)).add(number(spacing));
    if (options.crop) {
      const BoundingBox& b = *options.crop;
      args.add("-te").add(number(b.xmin)).add(number(b.ymin)).add(number(b.xmax)).add(number(b.ymax));
    }
    if (info.has_nodata) args.add("-srcnodata").add(number(info.nodata));
    // Cells the source does not cover are nodata, never zeros.
    args.add("-dstnodata").add(info.has_nodata ? number(info.nodata) : "-3.0e38");
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
    args.add("-of")
        .add("MEM")
        .add("-projwin")
        .add(number(b.xmin))
        .add(number(b.ymax))
        .add(number(b.xmax))
        .add(number(b.ymin));
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
    out_info->vertical_unit = info.vertical_unit;
    if (!out_info->has_nodata && info.has_nodata) {
      out_info->has_nodata = true;
      out_info->nodata = info.nodata;
    }
    if (warp) {
      out_info->has_nodata = true;
      out_info->nodata = info.has_nodata ? info.nodata : -3.0e38;
    }
  }
  VISVOL_RETURN_IF_ERROR(gdal::check_metric_grid(*out_info, path, options.max_posts, options.max_posts_reason));
  DemReadOptions read;
  read.nodata = options.nodata;
  read.max_posts = options.max_posts;
  Result<Heightfield> hf = gdal::to_heightfield(out, *out_info, path, read, info.vertical_to_m);
  if (!hf.ok()) return hf.status();
  if (info.vertical_to_m != 1.0) steps << "heights from " << info.vertical_unit << " to metres; ";
  if (info.vertical_unit.empty()) steps << "heights taken as metres (the file names no vertical unit); ";
  rep.output_crs = crs_name(hf->crs_wkt);
  rep.steps = steps.str();
  if (!rep.steps.empty()) rep.steps.resize(rep.steps.size() - 2);  // trailing "; "
  if (report) *report = rep;
  return hf;
}

Result<ImportGrid> import_grid(const std::string& path, const ImportOptions& options) {
  ImportOptions whole = options;
  whole.crop.reset();
  VISVOL_RETURN_IF_ERROR(validate(whole));
  Result<DatasetPtr> opened = gdal::open_raster(path, dem_drivers());
  if (!opened.ok()) return opened.status();
  Result<ImportPlan> plan = plan_import(**opened, path, whole);
  if (!plan.ok()) return plan.status();
  if (!plan->warp) return aligned_grid(plan->info);
  return warped_grid(plan->assumed ? *plan->assumed : **opened, *plan, path);
}

Result<BoundingBox> crop_for_area(const ImportGrid& grid, const BoundingBox& area, double margin_m,
                                  const std::string& option) {
  if (!is_box(area)) return invalid_argument(option + ": " + not_a_box(area));
  if (!(std::isfinite(margin_m) && margin_m >= 0)) {
    return invalid_argument(option + ": planning margin " + number(margin_m) + " m is not a finite number >= 0");
  }
  // The posts cover the area and margin; their pixels reach half a post further.
  const BoundingBox need = grown(area, margin_m + 0.5 * grid.spacing_m);
  VISVOL_RETURN_IF_ERROR(check_covered(grid.covered, need, area, margin_m, option));
  if (!grid.aligned) return whole_posts(need, grid.spacing_m);
  // A hair more keeps an edge that falls on a pixel edge from rounding inward;
  // the DEM's own edges (pixel edges too) stop it.
  const BoundingBox crop = snap_to_pixels(grid, grown(need, 1e-6 * grid.spacing_m));
  const BoundingBox& dem = grid.covered;
  return BoundingBox{std::max(crop.xmin, dem.xmin), std::max(crop.ymin, dem.ymin), std::min(crop.xmax, dem.xmax),
                     std::min(crop.ymax, dem.ymax)};
}

}  // namespace visvol::fields
