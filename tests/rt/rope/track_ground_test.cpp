// The highest terrain under a stretch of a path's track: exact against dense
// sampling, the ends of a stretch clamped to the track, a lone post between
// samples found.
#include "rt/rope/track_ground.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../fields/terrains.hpp"

namespace visvol::rt {
namespace {

// The highest ground at `samples` evenly spaced points of the stretch.
double sampled_highest(const fields::Heightfield& t, const std::vector<Vec3>& track, const TrackGround& g,
                       double from_m, double to_m, int samples) {
  double best = -1e300;
  for (int q = 0; q <= samples; ++q) {
    const double at = from_m + (to_m - from_m) * q / samples;
    std::size_t k = 1;
    while (k + 1 < track.size() && g.at_vertex_m(static_cast<int>(k)) < at) ++k;
    const double a = g.at_vertex_m(static_cast<int>(k - 1)), b = g.at_vertex_m(static_cast<int>(k));
    const double u = b > a ? (at - a) / (b - a) : 0.0;
    const Vec3 p = track[k - 1] + u * (track[k] - track[k - 1]);
    best = std::max(best, fields::bilinear_height(t, t.i_of(p.x()), t.j_of(p.y())));
  }
  return best;
}

TEST(TrackGround, TheHighestOfAStretchIsTheDenselySampledHighest) {
  const fields::Heightfield t = fields::testing::fractal(64, 11, 30.0, 200.0);
  std::mt19937 rng(39);
  std::uniform_real_distribution<double> post(2, 61), unit(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> track;
    for (int k = 0; k < 6; ++k) track.emplace_back(t.x_of(post(rng)), t.y_of(post(rng)), 1000.0 * unit(rng));
    const TrackGround g(t, track.data(), static_cast<int>(track.size()));
    double along = 0;
    for (std::size_t k = 1; k < track.size(); ++k) {
      along += std::hypot(track[k].x() - track[k - 1].x(), track[k].y() - track[k - 1].y());
      EXPECT_NEAR(g.at_vertex_m(static_cast<int>(k)), along, 1e-9);  // horizontal, heights ignored
    }
    for (int q = 0; q < 10; ++q) {
      const double a = g.length_m() * unit(rng), b = std::min(g.length_m(), a + 200.0 * unit(rng));
      const double exact = g.highest_m(a, b), sampled = sampled_highest(t, track, g, a, b, 20000);
      EXPECT_GE(exact, sampled - 1e-9) << "trial " << trial;  // nothing sampled is higher
      EXPECT_LE(exact, sampled + 1e-3) << "trial " << trial;  // and it is there
    }
  }
}

TEST(TrackGround, AStretchIsClampedToTheTrackAndALonePostIsFound) {
  fields::Heightfield t = fields::testing::blank(20, 5, 10.0, 0.0f);
  t.at(10, 2) = 40.0f;  // a mast on a plain, under the track
  const std::vector<Vec3> track = {{t.x_of(1), t.y_of(2), 50}, {t.x_of(18), t.y_of(2), 50}};
  const TrackGround g(t, track.data(), 2);
  EXPECT_DOUBLE_EQ(g.length_m(), 170.0);
  EXPECT_DOUBLE_EQ(g.highest_m(85.0, 95.0), 40.0);   // the mast, between any samples
  EXPECT_DOUBLE_EQ(g.highest_m(0.0, 80.0), 0.0);     // the plain before it
  EXPECT_DOUBLE_EQ(g.highest_m(-1e9, 1e9), 40.0);    // clamped to the track
  EXPECT_DOUBLE_EQ(g.highest_m(95.0, 85.0), 20.0);   // a stretch of nothing: the ground at its end
  EXPECT_DOUBLE_EQ(g.highest_m(90.0, 100.0), 40.0);  // the mast at its start
  EXPECT_DOUBLE_EQ(g.highest_m(100.0, 200.0), 0.0);  // one post on: the plain
}

// A climb on the spot (a leg of no horizontal length) adds no track; one
// vertex is a track of no length; a leg with a coordinate that is not
// finite adds no ground (the checker refuses such paths before).
TEST(TrackGround, LegsOfNoLengthAndOneVertexAreTracksOfNoLength) {
  fields::Heightfield t = fields::testing::blank(20, 5, 10.0, 0.0f);
  t.at(10, 2) = 40.0f;
  const Vec3 a{t.x_of(5), t.y_of(2), 50}, b{t.x_of(15), t.y_of(2), 50};
  const std::vector<Vec3> on_the_spot = {a, a + Vec3(0, 0, 30), b, b + Vec3(0, 0, 10)};
  const TrackGround g(t, on_the_spot.data(), 4);
  EXPECT_DOUBLE_EQ(g.at_vertex_m(1), 0.0);
  EXPECT_DOUBLE_EQ(g.at_vertex_m(3), 100.0);
  EXPECT_DOUBLE_EQ(g.highest_m(0.0, 100.0), 40.0);
  EXPECT_DOUBLE_EQ(g.highest_m(60.0, 100.0), 0.0);
  const TrackGround one(t, &a, 1);
  EXPECT_DOUBLE_EQ(one.length_m(), 0.0);
  EXPECT_DOUBLE_EQ(one.highest_m(-5.0, 5.0), 0.0);  // the ground under it
  const std::vector<Vec3> broken = {a, Vec3(NAN, t.y_of(2), 50), b};
  const TrackGround nan_leg(t, broken.data(), 3);
  EXPECT_DOUBLE_EQ(nan_leg.length_m(), 0.0);
  const double none = nan_leg.highest_m(0.0, 10.0);
  EXPECT_TRUE(std::isinf(none) && none < 0) << none;  // no ground at all, never a height
}

}  // namespace
}  // namespace visvol::rt
