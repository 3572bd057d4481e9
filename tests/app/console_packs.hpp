// The console tests' packs: small, two levels of detail (console_test,
// console_threads_test).
#pragma once

#include "storage/pack_build.hpp"

namespace visvol::app::testing {

inline storage::PackBuildParams small_pack_params() {
  storage::PackBuildParams p;
  p.field.nz = 32;
  p.field.ceiling_m = 200;
  p.field.range_posts = 8;
  p.lod_levels = 2;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  return p;
}

}  // namespace visvol::app::testing
