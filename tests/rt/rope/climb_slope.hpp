// The tailwind climb of path_check_test (ClimbInATailwind) and
// envelope_fit_test (FitFlights): a plain at 100 m (400 x 40 posts of 5 m)
// rising 0.26 m a metre from 520 m to 900 m along x, and a path up it on
// post row 20: 130 m to 500 m, a climb of 104 m over 400 m (14.6 deg), then
// level at 234 m, the slope 20 m behind it and 35.2 m under its legs.
#pragma once

#include <algorithm>
#include <vector>

#include "../../fields/terrains.hpp"
#include "rt/rope/rope.hpp"

namespace visvol::rt::testing {

struct ClimbSlope {
  fields::Heightfield terrain = fields::testing::blank(400, 40, 5.0, 100.0f);
  std::vector<Vec3> path;
  ClimbSlope() {
    for (int j = 0; j < terrain.ny; ++j) {
      for (int i = 0; i < terrain.nx; ++i) {
        terrain.at(i, j) = static_cast<float>(100.0 + std::clamp((i - 104) * 5.0, 0.0, 380.0) * 0.26);
      }
    }
    path = {post(20, 130), post(100, 130), post(180, 234), post(380, 234)};
  }
  Vec3 post(double i, double z) const { return {terrain.x_of(i), terrain.y_of(20), z}; }
};

}  // namespace visvol::rt::testing
