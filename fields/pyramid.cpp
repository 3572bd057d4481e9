#include "fields/pyramid.hpp"

#include <sstream>

namespace visvol::fields {

namespace {

std::vector<float> downsample_weights(const std::vector<float>& w, int nx, int ny) {
  if (w.empty()) return w;
  const int cx = nx / 2, cy = ny / 2;
  std::vector<float> out(static_cast<std::size_t>(cx) * static_cast<std::size_t>(cy));
  auto at = [&](int i, int j) {
    return w[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)];
  };
  for (int j = 0; j < cy; ++j) {
    for (int i = 0; i < cx; ++i) {
      out[static_cast<std::size_t>(j) * static_cast<std::size_t>(cx) + static_cast<std::size_t>(i)] =
          0.25f * (at(2 * i, 2 * j) + at(2 * i + 1, 2 * j) + at(2 * i, 2 * j + 1) + at(2 * i + 1, 2 * j + 1));
    }
  }
  return out;
}

}  // namespace

Result<std::vector<LodInput>> lod_inputs(const Heightfield& hf, const FieldParams& params, int levels) {
  VISVOL_RETURN_IF_ERROR(validate(hf, "heightfield"));
  VISVOL_RETURN_IF_ERROR(validate(params, hf));
  if (levels < 1 || levels > 16) {
    return invalid_argument("levels of detail: " + std::to_string(levels) + " is outside 1..16");
  }
  std::vector<LodInput> out;
  out.reserve(static_cast<std::size_t>(levels));
  LodInput first{hf, params};
  const VolumeGeometry g0 = volume_geometry(hf, params);
  first.params.vertical = VerticalGrid{g0.z0_m, g0.dz_m};
  out.push_back(std::move(first));
  for (int level = 1; level < levels; ++level) {
    const LodInput& fine = out.back();
    if (fine.terrain.nx / 2 < kMinLevelPosts || fine.terrain.ny / 2 < kMinLevelPosts) {
      std::ostringstream msg;
      msg << "levels of detail: level " << level << " of a " << hf.nx << " x " << hf.ny << " grid would have "
          << fine.terrain.nx / 2 << " x " << fine.terrain.ny / 2 << " posts, fewer than " << kMinLevelPosts
          << " a side; use at most " << level << " levels";
      return invalid_argument(msg.str());
    }
    LodInput coarse{downsample2(fine.terrain), fine.params};
    coarse.params.weights = downsample_weights(fine.params.weights, fine.terrain.nx, fine.terrain.ny);
    out.push_back(std::move(coarse));
  }
  return out;
}

Result<std::vector<LodLevel>> build_pyramid_dense(const Heightfield& hf, const FieldParams& params, int levels,
                                                  const ProgressFn& progress, std::vector<BuildStats>* stats) {
  Result<std::vector<LodInput>> inputs = lod_inputs(hf, params, levels);
  if (!inputs.ok()) return inputs.status();
  // Work per level shrinks about 4x per level; weight progress accordingly.
  double total = 0, done = 0;
  for (const LodInput& in : *inputs) total += static_cast<double>(in.terrain.size());
  std::vector<LodLevel> out;
  for (LodInput& in : *inputs) {
    const double share = static_cast<double>(in.terrain.size()) / total;
    BuildStats level_stats;
    Result<DenseVolume> field = build_visibility_dense(
        in.terrain, in.params,
        [&](double f) {
          if (progress) progress(done + share * f);
        },
        &level_stats);
    if (!field.ok()) {
      return field.status().with_context("level of detail " + std::to_string(out.size()));
    }
    done += share;
    if (stats) stats->push_back(level_stats);
    out.push_back(LodLevel{std::move(in.terrain), std::move(*field)});
  }
  return out;
}

}  // namespace visvol::fields
