// Positions and heights between a pack's CRS and WGS84 (wgs84.hpp).
#include "wgs84.hpp"

#include <ogr_spatialref.h>
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

#include "path_io_detail.hpp"

namespace visvol::cli {

using detail::shown;

std::optional<bool> projected_in_metres(const std::string& crs_wkt) {
  OGRSpatialReference srs;
  if (srs.importFromWkt(crs_wkt.c_str()) != OGRERR_NONE) return std::nullopt;
  // a CRS in degrees (or feet) would place the grid wrong
  return srs.IsProjected() && std::fabs(srs.GetLinearUnits() - 1.0) <= 1e-9;
}

namespace {

struct ProjContextFree {
  void operator()(PJ_CONTEXT* c) const { proj_context_destroy(c); }
};
struct ProjFree {
  void operator()(PJ* p) const { proj_destroy(p); }
};
using ProjContext = std::unique_ptr<PJ_CONTEXT, ProjContextFree>;
using ProjObject = std::unique_ptr<PJ, ProjFree>;

// A pack's CRS must be projected, in metres, as its grid is.
Status check_pack_crs(const std::string& crs_wkt) {
  if (crs_wkt.empty()) return Status(Errc::unsupported, "the pack has no CRS, so there is no WGS84 position");
  const std::optional<bool> metres = projected_in_metres(crs_wkt);
  if (!metres) return corrupt("the CRS WKT does not parse");
  if (!*metres) {
    OGRSpatialReference pack;
    pack.importFromWkt(crs_wkt.c_str());
    return corrupt("the CRS (" + std::string(pack.GetName() ? pack.GetName() : "unnamed") +
                   ") is not a projected CRS in metres, as a pack's grid is");
  }
  return Status::ok_status();
}

// PROJ's transformation between the pack's CRS and WGS84, x east and y north
// (longitude first) on both sides: at each point the most accurate one whose
// area holds it and whose grids are installed (no network). It keeps the
// coarsest operation it used, to say how far WGS84 positions can be trusted
// (NAD27 without NOAA's grid: a datum shift good to 7 m).
class Wgs84Transform {
 public:
  static Result<Wgs84Transform> create(const std::string& crs_wkt) {
    VISVOL_RETURN_IF_ERROR(check_pack_crs(crs_wkt));
    Wgs84Transform t;
    t.ctx_.reset(proj_context_create());
    if (!t.ctx_) return resource_error("PROJ: no context");
    proj_log_level(t.ctx_.get(), PJ_LOG_NONE);  // failures are reported in words
    proj_context_set_enable_network(t.ctx_.get(), 0);
    const ProjObject pack(proj_create(t.ctx_.get(), crs_wkt.c_str())), wgs84(proj_create(t.ctx_.get(), "EPSG:4326"));
    if (!pack || !wgs84) return Status(Errc::unsupported, "PROJ does not read the CRS or know EPSG:4326");
    const ProjObject any_order(proj_create_crs_to_crs_from_pj(t.ctx_.get(), pack.get(), wgs84.get(), nullptr, nullptr));
    if (any_order) t.pj_.reset(proj_normalize_for_visualization(t.ctx_.get(), any_order.get()));
    if (!t.pj_) return Status(Errc::unsupported, "no transformation between the CRS and WGS84");
    return t;
  }

  // False when the point does not convert.
  bool convert(double& x, double& y, bool to_wgs84) {
    // no time (HUGE_VAL): a time-dependent transformation would take year 0
    const PJ_COORD in = proj_coord(x, y, 0, HUGE_VAL);
    const PJ_DIRECTION direction = to_wgs84 ? PJ_FWD : PJ_INV;
    const PJ_COORD r = proj_trans(pj_.get(), direction, in);
    if (!std::isfinite(r.xy.x) || !std::isfinite(r.xy.y) || r.xy.x == HUGE_VAL) return false;
    x = r.xy.x;
    y = r.xy.y;
    // which operation PROJ took costs 45 us a point to ask (a copy of it):
    // asked again only where the last one's answer differs from this one's
    if (last_op_) {
      const PJ_COORD same = proj_trans(last_op_.get(), direction, in);
      if (same.xy.x == r.xy.x && same.xy.y == r.xy.y) return true;
    }
    note_operation();
    return true;
  }

  const Wgs84Conversion& coarsest() const { return coarsest_; }

 private:
  void note_operation() {
    last_op_.reset(proj_trans_get_last_used_operation(pj_.get()));
    const PJ* op = last_op_.get();
    if (op == nullptr) {
      if (coarsest_.operation.empty()) coarsest_ = {"a transformation PROJ does not name", -1};
      return;
    }
    const char* name = proj_get_name(op);
    if (name != nullptr && name == last_name_) return;
    last_name_ = name != nullptr ? name : "";
    // the longitude-first order is ours, not the transformation's
    const std::string order = " + axis order change (2D)";
    std::string shown_name = last_name_;
    if (shown_name.size() > order.size() &&
        shown_name.compare(shown_name.size() - order.size(), order.size(), order) == 0)
      shown_name.resize(shown_name.size() - order.size());
    const double accuracy = proj_coordoperation_get_accuracy(ctx_.get(), op);
    // a pure change of projection is exact; PROJ says -1 (unknown) for some
    const bool exact =
        proj_get_type(op) == PJ_TYPE_CONVERSION || (accuracy < 0 && last_name_.find(" to ") == std::string::npos);
    const double a = exact ? 0.0 : accuracy;
    const bool coarser = coarsest_.operation.empty() || (a < 0 && coarsest_.accuracy_m >= 0) ||
                         (coarsest_.accuracy_m >= 0 && a > coarsest_.accuracy_m);
    if (coarser) coarsest_ = {shown_name, a};
  }

  ProjContext ctx_;
  ProjObject pj_;
  ProjObject last_op_;  // the operation PROJ took for the last point asked
  std::string last_name_;
  Wgs84Conversion coarsest_;
};

// Heights stay the DEM's (mean sea level) both ways.
Result<std::vector<Vec3>> transform_xy(const std::vector<Vec3>& points, const std::string& crs_wkt, bool to_wgs84,
                                       Wgs84Conversion* conversion = nullptr) {
  Result<Wgs84Transform> ct = Wgs84Transform::create(crs_wkt);
  if (!ct.ok()) return ct.status();
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    double x = points[i].x(), y = points[i].y();
    if (!std::isfinite(x) || !std::isfinite(y) || !ct->convert(x, y, to_wgs84)) {
      return invalid_argument("path vertex " + std::to_string(i) + " cannot be converted " +
                              (to_wgs84 ? "to WGS84" : "from WGS84 to the pack's CRS"));
    }
    if (to_wgs84 && !(std::fabs(x) <= 180 && std::fabs(y) <= 90)) {
      return invalid_argument("path vertex " + std::to_string(i) + " converts to longitude " + shown(x, 6) +
                              ", latitude " + shown(y, 6) + ": not a WGS84 position");
    }
    out.push_back({x, y, points[i].z()});
  }
  if (conversion != nullptr) *conversion = ct->coarsest();
  return out;
}

}  // namespace

Result<std::vector<Vec3>> to_wgs84(const std::vector<Vec3>& vertices, const std::string& crs_wkt,
                                   Wgs84Conversion* conversion) {
  return transform_xy(vertices, crs_wkt, true, conversion);
}

Result<std::vector<Vec3>> from_wgs84(const std::vector<Vec3>& lon_lat_h, const std::string& crs_wkt,
                                     Wgs84Conversion* conversion) {
  return transform_xy(lon_lat_h, crs_wkt, false, conversion);
}

std::string Wgs84Conversion::describe() const {
  if (accuracy_m == 0) return operation + " (exact)";
  if (accuracy_m < 0) return operation + " (accuracy not known)";
  char text[32];
  std::snprintf(text, sizeof text, "%g", accuracy_m);
  return operation + " (accurate to " + text + " m by EPSG)";
}

std::string wgs84_accuracy_note(const Wgs84Conversion& c) {
  if (c.operation.empty() || (c.accuracy_m >= 0 && c.accuracy_m <= kTrustedWgs84AccuracyM)) return {};
  return "WGS84 positions by " + c.describe() +
         ", the finest transformation PROJ has here: the path in WGS84 and the path on the pack's terrain may "
         "lie that far apart";
}

// ---- Heights: EGM96 orthometric <-> WGS84 ellipsoidal ----

namespace {

constexpr const char* kOrthometricCrs = "EPSG:4326+5773";  // WGS 84 + EGM96 height
constexpr const char* kEllipsoidalCrs = "EPSG:4979";       // WGS 84 (3D): height above the ellipsoid
// The grid PROJ's EPSG transformation uses, and its name before PROJ 7.
constexpr const char* kGeoidGridNames = "us_nga_egm96_15.tif (egm96_15.gtx before PROJ 7)";

struct ProjListFree {
  void operator()(PJ_OBJ_LIST* l) const { proj_list_destroy(l); }
};
struct ProjFactoryFree {
  void operator()(PJ_OPERATION_FACTORY_CONTEXT* f) const { proj_operation_factory_context_destroy(f); }
};
Status geoid_missing(const std::string& grids) {
  return Status(Errc::unsupported,
                "the EGM96 geoid grid " + grids +
                    " is not installed in PROJ's data folder (Debian: proj-data, /usr/share/proj; or PROJ_DATA): "
                    "heights above the WGS84 ellipsoid (GeoJSON, RFC 7946) need it");
}

}  // namespace

// Orthometric (EGM96) to ellipsoidal heights (WGS84) or back at WGS84
// (longitude, latitude, height) points: the EPSG transformation through the
// EGM96 grid, never PROJ's "ballpark" one that leaves heights unchanged, and
// no grid fetched from the network. A context of its own per call (GDAL keeps
// its own), so this is thread-compatible.
Result<GeoidShift> shift_heights(const std::vector<Vec3>& lon_lat_h, bool to_ellipsoidal) {
  const ProjContext ctx(proj_context_create());
  if (!ctx) return resource_error("PROJ: no context");
  proj_log_level(ctx.get(), PJ_LOG_NONE);  // failures are reported below, in words
  proj_context_set_enable_network(ctx.get(), 0);
  const ProjObject source(proj_create(ctx.get(), kOrthometricCrs)), target(proj_create(ctx.get(), kEllipsoidalCrs));
  if (!source || !target) {
    return Status(Errc::unsupported, std::string("PROJ does not know ") + kOrthometricCrs + " or " + kEllipsoidalCrs +
                                         " (is its database proj.db installed?)");
  }
  const std::unique_ptr<PJ_OPERATION_FACTORY_CONTEXT, ProjFactoryFree> factory(
      proj_create_operation_factory_context(ctx.get(), nullptr));
  if (!factory) return resource_error("PROJ: no operation factory");
  proj_operation_factory_context_set_allow_ballpark_transformations(ctx.get(), factory.get(), 0);
  // list the transformations whether their grids are here or not, to name a missing one
  proj_operation_factory_context_set_grid_availability_use(ctx.get(), factory.get(), PROJ_GRID_AVAILABILITY_IGNORED);
  proj_operation_factory_context_set_spatial_criterion(ctx.get(), factory.get(),
                                                       PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  const std::unique_ptr<PJ_OBJ_LIST, ProjListFree> operations(
      proj_create_operations(ctx.get(), source.get(), target.get(), factory.get()));
  const int count = operations ? proj_list_get_count(operations.get()) : 0;
  ProjObject chosen;
  std::string grid, missing;
  for (int i = 0; i < count && !chosen; ++i) {
    ProjObject op(proj_list_get(ctx.get(), operations.get(), i));
    if (!op) continue;
    const int grids = proj_coordoperation_get_grid_used_count(ctx.get(), op.get());
    bool available = grids > 0;  // a transformation without a grid does not apply the geoid
    std::string names;
    for (int g = 0; g < grids; ++g) {
      const char *short_name = nullptr, *full_name = nullptr, *package = nullptr, *url = nullptr;
      int direct_download = 0, open_license = 0, here = 0;
      if (!proj_coordoperation_get_grid_used(ctx.get(), op.get(), g, &short_name, &full_name, &package, &url,
                                             &direct_download, &open_license, &here)) {
        available = false;
        continue;
      }
      names += (names.empty() ? "" : ", ") + std::string(short_name != nullptr ? short_name : "?");
      if (here == 0) available = false;
    }
    if (available) {
      chosen.reset(proj_normalize_for_visualization(ctx.get(), op.get()));  // longitude, latitude order
      grid = names;
    } else if (missing.empty() && !names.empty()) {
      missing = names;
    }
  }
  if (!chosen) return geoid_missing(missing.empty() ? kGeoidGridNames : missing);

  GeoidShift out;
  out.grid = grid;
  out.points.reserve(lon_lat_h.size());
  for (std::size_t i = 0; i < lon_lat_h.size(); ++i) {
    const Vec3& p = lon_lat_h[i];
    const PJ_COORD shifted =
        proj_trans(chosen.get(), to_ellipsoidal ? PJ_FWD : PJ_INV, proj_coord(p.x(), p.y(), p.z(), 0));
    if (!std::isfinite(shifted.xyz.z) || shifted.xyz.z == HUGE_VAL) {
      const int err = proj_context_errno(ctx.get());
      return invalid_argument("point " + std::to_string(i) + " (longitude " + shown(p.x(), 6) + ", latitude " +
                              shown(p.y(), 6) + "): no EGM96 geoid height there" +
                              (err != 0 ? std::string(" (") + proj_context_errno_string(ctx.get(), err) + ")" : ""));
    }
    out.points.push_back({p.x(), p.y(), shifted.xyz.z});
  }
  return out;
}

Result<std::vector<Vec3>> orthometric_to_ellipsoidal(const std::vector<Vec3>& lon_lat_h) {
  Result<GeoidShift> s = shift_heights(lon_lat_h, true);
  if (!s.ok()) return s.status();
  return std::move(s->points);
}

Result<std::vector<Vec3>> ellipsoidal_to_orthometric(const std::vector<Vec3>& lon_lat_h) {
  Result<GeoidShift> s = shift_heights(lon_lat_h, false);
  if (!s.ok()) return s.status();
  return std::move(s->points);
}

}  // namespace visvol::cli
