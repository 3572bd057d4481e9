// visvol viewshed DEM --observer X Y -o OUT.tif: one observer's viewshed.
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include "cli.hpp"
#include "commands.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/viewshed.hpp"
#include "import_cli.hpp"
#include "io/atomic_file.hpp"

namespace visvol::cli {

namespace {

struct ViewshedOptions {
  std::string dem;
  std::string out;
  std::vector<double> observer;
  fields::ViewshedParams params;
  ImportCli import;
};

int run_viewshed(ViewshedOptions& o) {
  if (Status s = check_output_path(o.out); !s.ok()) return fail("viewshed", s.with_context("-o"));
  if (Status s = output_is_no_input(o.out, "-o", {{"DEM", o.dem}}); !s.ok()) return fail("viewshed", s);
  const auto t0 = std::chrono::steady_clock::now();
  fields::ImportReport imported;
  Result<fields::Heightfield> hf = import(o.dem, o.import, &imported);
  if (!hf.ok()) return fail("viewshed", hf.status());
  o.params.observer_x = o.observer[0];
  o.params.observer_y = o.observer[1];
  Result<fields::Viewshed> vs = fields::compute_viewshed(*hf, o.params);
  if (!vs.ok()) return fail("viewshed", vs.status());
  const double compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Status written = fields::write_geotiff_u8(o.out, *hf, vs->value, fields::kViewshedOutside);
  if (!written.ok()) return fail("viewshed", written);
  std::size_t visible = 0, in_range = 0;
  for (std::uint8_t v : vs->value) {
    visible += v == fields::kViewshedVisible;
    in_range += v != fields::kViewshedOutside;
  }
  std::printf("observer post (%d, %d) at (%.1f, %.1f), ground %.1f m, eye %+.2f m, target %+.2f m\n", vs->observer_i,
              vs->observer_j, hf->x_of(vs->observer_i), hf->y_of(vs->observer_j),
              hf->at(vs->observer_i, vs->observer_j), o.params.observer_height_m, o.params.target_height_m);
  std::printf("visible    %zu of %zu cells in range (%.1f%%)\n", visible, in_range,
              in_range ? 100.0 * double(visible) / double(in_range) : 0.0);
  std::printf("written    %s (GeoTIFF, 1 visible, 0 hidden, 255 out of range)\n", o.out.c_str());
  std::printf("time       %.3f s\n", compute_s);
  return kExitOk;
}

}  // namespace

Runner add_viewshed_command(CLI::App& app) {
  auto o = std::make_shared<ViewshedOptions>();
  CLI::App* c =
      app.add_subcommand("viewshed", "Write the viewshed of one observer as a GeoTIFF (same hull as the field)");
  c->add_option("DEM", o->dem, "Terrain: GeoTIFF, SRTM .hgt, USGS .dem, ESRI or GRASS ASCII grid, DTED")->required();
  c->add_option("--observer", o->observer,
                "Observer position X Y in the output CRS (the DEM's, or --t-srs, or its UTM zone), m")
      ->expected(2)
      ->required();
  c->add_option("-o,--output", o->out, "Output GeoTIFF")->required();
  c->add_option("--observer-height", o->params.observer_height_m, "Eye above the ground, m")->capture_default_str();
  c->add_option("--target-height", o->params.target_height_m, "Target above the ground, m")->capture_default_str();
  c->add_option("--max-distance", o->params.max_distance_m, "Range, m (0: unlimited; at most 1e8)")
      ->capture_default_str();
  c->add_option("--curvature", o->params.curvature_coeff,
                "Earth curvature and refraction coefficient, 0 off (0.85714 is usual)")
      ->capture_default_str();
  c->add_option("--exact-rings", o->params.exact_rings, "Rings evaluated exactly")->capture_default_str();
  add_import_options(c, o->import);
  return [o] { return run_viewshed(*o); };
}

}  // namespace visvol::cli
