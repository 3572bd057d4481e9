#include "storage/pack_build.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fields/terrain_force.hpp"
#include "fields/worker_pool.hpp"
#include "io/json_text.hpp"
#include "storage/pack_writer.hpp"

#ifndef VISVOL_VERSION
#define VISVOL_VERSION "unknown"
#endif

namespace visvol::storage {

// The band the build validates (fields) is the band the format holds.
static_assert(kMaxBandLevels == fields::kMaxBandLevels && kMaxBandOffsetM == fields::kMaxBandOffsetM &&
              kMinBandOffsetM == fields::kMinBandOffsetM);

namespace {

using fields::Heightfield;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Height or area tiles of one level, tile rows [rows.first, rows.end).
Status write_2d(TileSink& w, int level, Layer layer, const Heightfield& hf, const std::vector<float>& values,
                TileRows rows) {
  const TileGrid g = tile_grid(layer, hf.nx, hf.ny);
  std::vector<float> tile(static_cast<std::size_t>(kTile2dPosts * kTile2dPosts));
  for (int ty = rows.first; ty < rows.end; ++ty) {
    for (int tx = 0; tx < g.tiles_x; ++tx) {
      std::fill(tile.begin(), tile.end(), 0.0f);
      for (int y = 0; y < kTile2dPosts; ++y) {
        const int j = ty * kTile2dPosts + y;
        if (j >= hf.ny) break;
        for (int x = 0; x < kTile2dPosts; ++x) {
          const int i = tx * kTile2dPosts + x;
          if (i >= hf.nx) break;
          tile[static_cast<std::size_t>(y * kTile2dPosts + x)] =
              values[static_cast<std::size_t>(j) * static_cast<std::size_t>(hf.nx) + static_cast<std::size_t>(i)];
        }
      }
      VISVOL_RETURN_IF_ERROR(w.write_tile(level, layer, tx, ty, tile.data(), tile.size() * sizeof(float)));
    }
  }
  return Status::ok_status();
}

// Collects field rows into bands of kBrickPosts rows and writes each band's
// bricks as soon as it is complete. Rows may come in any order (a build split
// by observers finishes the rows near its band's edges last); a band waits
// in memory until its last row.
class BrickSink final : public fields::VolumeRowSink {
 public:
  // The bricks of a band are encoded by `pool` (the field build's own pool is
  // idle while its rows leave).
  BrickSink(TileSink& w, std::size_t brick_bytes, int level, int nx, int ny, int nz, VisibilityEncoding enc,
            fields::WorkerPool& pool)
      : w_(w),
        level_(level),
        nx_(nx),
        ny_(ny),
        nz_(nz),
        enc_(enc),
        pool_(pool),
        brick_bytes_(brick_bytes),
        bricks_(brick_bytes * static_cast<std::size_t>(tile_grid(Layer::visibility, nx, ny).tiles_x)) {}

  Status write_row(int j, const float* values) override {
    const int ty = j / kBrickPosts, y = j % kBrickPosts;
    BrickRow& band = rows_[ty];
    if (band.values.empty()) {
      band.values.assign(static_cast<std::size_t>(kBrickPosts) * row_floats(), 0.0f);
      band.missing = posts_high(ty);
    }
    std::memcpy(&band.values[static_cast<std::size_t>(y) * row_floats()], values, row_floats() * sizeof(float));
    if (--band.missing > 0) return Status::ok_status();
    const Status st = flush(ty, posts_high(ty), band.values);
    rows_.erase(ty);
    return st;
  }

 private:
  struct BrickRow {
    std::vector<float> values;  // kBrickPosts rows of nz x nx values
    int missing = 0;            // rows not yet written
  };
  std::size_t row_floats() const { return static_cast<std::size_t>(nz_) * static_cast<std::size_t>(nx_); }
  // Rows of brick row `ty` (the last may be short).
  int posts_high(int ty) const { return std::min(kBrickPosts, ny_ - ty * kBrickPosts); }

  Status flush(int ty, int rows, const std::vector<float>& band) {
    const int tiles_x = tile_grid(Layer::visibility, nx_, ny_).tiles_x;
    pool_.run(tiles_x,
              [&](int tx, int) { encode(tx, rows, band, &bricks_[static_cast<std::size_t>(tx) * brick_bytes_]); });
    for (int tx = 0; tx < tiles_x; ++tx) {
      VISVOL_RETURN_IF_ERROR(w_.write_tile(level_, Layer::visibility, tx, ty,
                                           &bricks_[static_cast<std::size_t>(tx) * brick_bytes_], brick_bytes_));
    }
    return Status::ok_status();
  }

  // Brick tx of a band of `rows` rows into `brick` (brick_bytes_).
  void encode(int tx, int rows, const std::vector<float>& band, std::uint8_t* brick) const {
    std::fill(brick, brick + brick_bytes_, std::uint8_t{0});
    for (int k = 0; k < nz_; ++k) {
      for (int y = 0; y < rows; ++y) {
        for (int x = 0; x < kBrickPosts; ++x) {
          const int i = tx * kBrickPosts + x;
          if (i >= nx_) break;
          const float f =
              band[static_cast<std::size_t>(y) * row_floats() +
                   static_cast<std::size_t>(k) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)];
          const std::size_t index = static_cast<std::size_t>((k * kBrickPosts + y) * kBrickPosts + x);
          if (enc_ == VisibilityEncoding::uint16) {
            const std::uint16_t q = quantise_visibility(f);
            std::memcpy(&brick[index * sizeof q], &q, sizeof q);
          } else {
            std::memcpy(&brick[index * sizeof f], &f, sizeof f);
          }
        }
      }
    }
  }

  TileSink& w_;
  int level_, nx_, ny_, nz_;
  VisibilityEncoding enc_;
  fields::WorkerPool& pool_;
  std::size_t brick_bytes_;
  std::map<int, BrickRow> rows_;      // brick rows being filled, by index
  std::vector<std::uint8_t> bricks_;  // one brick row's bricks, encoded
};

std::int16_t to_centimetres(float metres) {
  const double cm = std::round(static_cast<double>(metres) / kTffUnitM);
  return static_cast<std::int16_t>(std::clamp(cm, -32767.0, 32767.0));
}

// One terrain force field brick: tile tx of the band's rows (y rows of
// kBrickPosts posts each), in centimetres.
void tff_brick(const fields::TffSample* band, const Heightfield& hf, int band_levels, int tx, int y_rows,
               std::int16_t* brick, std::size_t brick_values) {
  const std::size_t nx = static_cast<std::size_t>(hf.nx);
  const std::size_t levels = static_cast<std::size_t>(band_levels);
  std::fill(brick, brick + brick_values, std::int16_t{0});
  for (int b = 0; b < band_levels; ++b) {
    for (int y = 0; y < y_rows; ++y) {
      for (int x = 0; x < kBrickPosts; ++x) {
        const int i = tx * kBrickPosts + x;
        if (i >= hf.nx) break;
        const fields::TffSample& s = band[(static_cast<std::size_t>(y) * levels + static_cast<std::size_t>(b)) * nx +
                                          static_cast<std::size_t>(i)];
        std::int16_t* dst = &brick[static_cast<std::size_t>(((b * kBrickPosts + y) * kBrickPosts + x) * 4)];
        dst[0] = to_centimetres(s.dx_m);
        dst[1] = to_centimetres(s.dy_m);
        dst[2] = to_centimetres(s.dz_m);
        dst[3] = to_centimetres(s.signed_distance_m);
      }
    }
  }
}

// Terrain force field bricks of one level, brick rows [rows.first, rows.end):
// a brick row's samples by the pool, then its bricks by the pool, written in
// order.
Status write_tff(TileSink& w, std::size_t brick_bytes, int level, const Heightfield& hf, const fields::TffParams& p,
                 TileRows rows, fields::WorkerPool& pool) {
  const TileGrid g = tile_grid(Layer::tff, hf.nx, hf.ny);
  const std::size_t nx = static_cast<std::size_t>(hf.nx);
  const std::size_t levels = static_cast<std::size_t>(p.band_levels);
  std::vector<fields::TffSample> band(static_cast<std::size_t>(kBrickPosts) * levels * nx);
  const std::size_t brick_values = brick_bytes / sizeof(std::int16_t);
  std::vector<std::int16_t> bricks(brick_values * static_cast<std::size_t>(g.tiles_x));
  for (int ty = rows.first; ty < rows.end; ++ty) {
    const int j0 = ty * kBrickPosts, j1 = std::min(hf.ny, j0 + kBrickPosts);
    fields::terrain_force_rows(hf, p, j0, j1, band.data(), &pool);
    pool.run(g.tiles_x, [&](int tx, int) {
      tff_brick(band.data(), hf, p.band_levels, tx, j1 - j0,
                bricks.data() + static_cast<std::size_t>(tx) * brick_values, brick_values);
    });
    for (int tx = 0; tx < g.tiles_x; ++tx) {
      VISVOL_RETURN_IF_ERROR(w.write_tile(level, Layer::tff, tx, ty,
                                          bricks.data() + static_cast<std::size_t>(tx) * brick_values, brick_bytes));
    }
  }
  return Status::ok_status();
}

Status check_source_json(const std::string& source_json) {
  if (source_json.empty() || nlohmann::json::accept(source_json)) return Status::ok_status();
  return invalid_argument("pack source description is not valid JSON");
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// The planning bounds the pack records, or why it cannot have any: a margin
// that is not a finite number >= 0, or one that leaves nothing of the grid.
Result<PlanningBounds> planning_bounds_for(const fields::VolumeGeometry& finest, const PackBuildParams& p) {
  std::ostringstream msg;
  const std::optional<double>& given = p.planning_margin_m;
  if (given && !(std::isfinite(*given) && *given >= 0)) {
    msg << "planning margin: " << *given << " m is not a finite number >= 0 (--planning-margin)";
    return invalid_argument(msg.str());
  }
  const fields::RangeShape shape = p.field.range_shape;
  const PlanningBounds bounds = planning_bounds_rule(finest, shape, p.field.range_posts, given);
  if (!bounds.box.empty()) return bounds;
  const fields::Bounds2D extent = post_extent(finest);
  msg << "planning bounds: ";
  if (given) {
    msg << "the --planning-margin of " << bounds.margin_m << " m";
  } else if (shape == fields::RangeShape::none) {
    msg << "the default margin of " << bounds.margin_m << " m";
  } else {
    msg << "the margin of the range, " << bounds.margin_m << " m (" << p.field.range_posts << " posts of "
        << finest.spacing_m << " m),";
  }
  msg << " on every side leaves nothing of the DEM's " << extent.xmax_m - extent.xmin_m << " x "
      << extent.ymax_m - extent.ymin_m << " m of posts; give a DEM wider than twice the margin"
      << (given ? ", or a smaller --planning-margin" : ", or a smaller --planning-margin or --range");
  return invalid_argument(msg.str());
}

std::string metadata(const Heightfield& hf, const PackBuildParams& p, const std::string& source_json,
                     const std::vector<fields::LodInput>& inputs, const PlanningBounds& planning) {
  nlohmann::json j;
  j["format"] = "visvol field pack";
  j["version"] = kPackVersion;
  j["tool"] = std::string("visvol ") + tool_version();
  j["created_utc"] = utc_now();
  j["crs_wkt"] = hf.crs_wkt;
  j["crs_name"] = p.crs_name;
  // GDAL geotransform of level 0's pixels (post (0, 0) is the first pixel's centre).
  j["geotransform"] = {hf.origin_x - 0.5 * hf.spacing_m, hf.spacing_m, 0.0,
                       hf.origin_y + 0.5 * hf.spacing_m, 0.0,          -hf.spacing_m};
  j["vertical_unit"] = "metre";
  j["source"] = source_json.empty() ? nlohmann::json::object() : nlohmann::json::parse(source_json);
  j["planning_bounds"] = planning_json(planning);
  const fields::FieldParams& f = p.field;
  j["build"] = {{"nz", f.nz},
                {"ceiling_m", f.ceiling_m},
                {"eye_height_m", f.eye_height_m},
                {"range_shape", fields::to_string(f.range_shape)},
                {"range_posts", f.range_posts},
                {"curvature_coeff", f.curvature_coeff},
                {"exact_rings", f.exact_rings},
                {"weights", !f.weights.empty()},
                {"levels_of_detail", p.lod_levels},
                {"visibility_encoding", p.encoding == VisibilityEncoding::uint16 ? "uint16" : "float32"},
                {"tff_band_offset_m", p.tff.band_offset_m},
                {"tff_band_levels", p.tff.band_levels}};
  for (const fields::LodInput& in : inputs) {
    j["levels"].push_back({{"nx", in.terrain.nx},
                           {"ny", in.terrain.ny},
                           {"spacing_m", in.terrain.spacing_m},
                           {"range_m", f.range_posts * in.terrain.spacing_m}});
  }
  return json_text(j, 2);
}

}  // namespace

const char* tool_version() { return VISVOL_VERSION; }

Status validate(const BuildShare& share) {
  if (share.count >= 1 && share.index >= 0 && share.index < share.count) return Status::ok_status();
  return invalid_argument("build share " + std::to_string(share.index) + " of " + std::to_string(share.count) +
                          " is not one of 0.." + std::to_string(share.count - 1));
}

TileRows share_tile_rows(int tiles_y, BuildShare share) {
  const auto at = [&](int i) {
    return static_cast<int>(static_cast<std::int64_t>(tiles_y) * i / std::max(share.count, 1));
  };
  return {at(share.index), at(share.index + 1)};
}

Result<PackPlan> plan_pack(const Heightfield& hf, const PackBuildParams& params) {
  VISVOL_RETURN_IF_ERROR(fields::validate(params.tff, hf.spacing_m));  // the finest level's reach is the most
  if (params.lod_levels < 1 || params.lod_levels > kMaxLodLevels) {
    return invalid_argument("levels of detail: " + std::to_string(params.lod_levels) + " is outside 1.." +
                            std::to_string(kMaxLodLevels));
  }
  PackPlan plan;
  Result<std::vector<fields::LodInput>> inputs = fields::lod_inputs(hf, params.field, params.lod_levels);
  if (!inputs.ok()) return inputs.status();
  plan.inputs = std::move(*inputs);
  // Check every level's memory plan before writing anything.
  for (const fields::LodInput& in : plan.inputs) {
    Result<fields::BuildPlan> memory = fields::plan_visibility_build(in.terrain, in.params);
    if (!memory.ok()) return memory.status();
  }
  plan.layout.encoding = params.encoding;
  plan.layout.band_levels = params.tff.band_levels;
  plan.layout.band_offset_m = params.tff.band_offset_m;
  for (const fields::LodInput& in : plan.inputs) {
    const fields::VolumeGeometry g = fields::volume_geometry(in.terrain, in.params);
    LevelEntry e{};
    e.nx = g.nx;
    e.ny = g.ny;
    e.nz = g.nz;
    e.range_posts = in.params.range_shape == fields::RangeShape::none ? 0 : in.params.range_posts;
    e.spacing_m = g.spacing_m;
    e.origin_x = g.origin_x;
    e.origin_y = g.origin_y;
    e.z0_m = g.z0_m;
    e.dz_m = g.dz_m;
    plan.layout.levels.push_back(e);
  }
  Result<PlanningBounds> planning =
      planning_bounds_for(fields::volume_geometry(plan.inputs.front().terrain, plan.inputs.front().params), params);
  if (!planning.ok()) return planning.status();
  plan.planning = *planning;
  return plan;
}

fields::RowBand share_field_rows(int nx, int ny, BuildShare share) {
  const TileRows bricks = share_tile_rows(tile_grid(Layer::visibility, nx, ny).tiles_y, share);
  return {std::min(ny, bricks.first * kBrickPosts), std::min(ny, bricks.end * kBrickPosts)};
}

namespace {

// Every share's rows of F_p at a level of `t`'s size, in order: they cover the rows.
std::vector<fields::RowBand> share_field_bands(const Heightfield& t, int count) {
  std::vector<fields::RowBand> bands;
  for (int q = 0; q < count; ++q) bands.push_back(share_field_rows(t.nx, t.ny, BuildShare{q, count}));
  return bands;
}

}  // namespace

Status build_pack_share(const PackPlan& plan, const PackBuildParams& params, BuildShare share, TileSink& sink,
                        const fields::ProgressFn& progress, PackBuildReport* report) {
  const auto t0 = Clock::now();
  VISVOL_RETURN_IF_ERROR(validate(share));
  // Progress: the field is most of the work; the terrain force field the rest.
  double total = 0, done = 0;
  for (const fields::LodInput& in : plan.inputs) total += static_cast<double>(in.terrain.size());
  fields::WorkerPool pool(params.field.threads);
  PackBuildReport local;
  for (std::size_t l = 0; l < plan.inputs.size(); ++l) {
    const fields::LodInput& in = plan.inputs[l];
    const Heightfield& t = in.terrain;
    const int level = static_cast<int>(l);
    const double share_of_total = static_cast<double>(t.size()) / total;
    const TileRows flat = share_tile_rows(tile_grid(Layer::height, t.nx, t.ny).tiles_y, share);
    const TileRows bricks = share_tile_rows(tile_grid(Layer::visibility, t.nx, t.ny).tiles_y, share);
    if (flat.first < flat.end) {
      VISVOL_RETURN_IF_ERROR(write_2d(sink, level, Layer::height, t, t.height_m, flat));
      VISVOL_RETURN_IF_ERROR(write_2d(sink, level, Layer::area, t, fields::area_factor(t), flat));
    }
    fields::BuildStats stats;
    if (bricks.first < bricks.end) {
      BrickSink bricks_out(sink, payload_bytes(plan.layout, level, Layer::visibility), level, t.nx, t.ny, in.params.nz,
                           params.encoding, pool);
      const fields::ProgressFn field_progress = [&](double f) {
        if (progress) progress(done + share_of_total * 0.9 * f);
      };
      Status st = share.exchange
                      ? fields::build_visibility_share(t, in.params, share_field_bands(t, share.count), share.index,
                                                       *share.exchange, bricks_out, field_progress, &stats)
                      : fields::build_visibility_rows(t, in.params, share_field_rows(t.nx, t.ny, share), bricks_out,
                                                      field_progress, &stats);
      if (!st.ok()) return st.with_context("level of detail " + std::to_string(level));
      const auto t_tff = Clock::now();
      VISVOL_RETURN_IF_ERROR(
          write_tff(sink, payload_bytes(plan.layout, level, Layer::tff), level, t, params.tff, bricks, pool));
      local.tff_s += seconds_since(t_tff);
    }
    local.levels.push_back(stats);
    done += share_of_total;
    if (progress) progress(done);
  }
  local.planning = plan.planning;
  local.wall_s = seconds_since(t0);
  if (report) *report = local;
  return Status::ok_status();
}

Result<std::string> pack_metadata(const Heightfield& hf, const PackBuildParams& params, const std::string& source_json,
                                  const PackPlan& plan) {
  VISVOL_RETURN_IF_ERROR(check_source_json(source_json));
  return metadata(hf, params, source_json, plan.inputs, plan.planning);
}

Status build_pack(const Heightfield& hf, const PackBuildParams& params, const std::string& source_json,
                  const std::string& out_path, const fields::ProgressFn& progress, PackBuildReport* report) {
  const auto t0 = Clock::now();
  VISVOL_RETURN_IF_ERROR(check_source_json(source_json));  // before any work
  Result<PackPlan> plan = plan_pack(hf, params);
  if (!plan.ok()) return plan.status();
  Result<std::unique_ptr<PackWriter>> writer = PackWriter::create(out_path, plan->layout);
  if (!writer.ok()) return writer.status();
  PackWriter& w = **writer;
  PackBuildReport local;
  VISVOL_RETURN_IF_ERROR(build_pack_share(*plan, params, BuildShare{}, w, progress, &local));
  Result<std::string> meta = pack_metadata(hf, params, source_json, *plan);
  if (!meta.ok()) return meta.status();
  VISVOL_RETURN_IF_ERROR(w.finish(*meta));
  local.file_bytes = w.file_bytes();
  local.planning.recorded = true;
  local.wall_s = seconds_since(t0);
  if (report) *report = local;
  return Status::ok_status();
}

}  // namespace visvol::storage
