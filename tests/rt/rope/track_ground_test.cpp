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

// The held stretches of a path's legs (where an autopilot taking each
// waypoint R early flies between two waypoints' heights) tile its track up
// to R before its end (the end's own height, and the mission's next item,
// from there): each from R before its leg's start to R before its end, those
// of legs within R of the start empty.
TEST(TrackGround, HeldStretchesTileTheTrack) {
  const fields::Heightfield t = fields::testing::fractal(64, 12, 30.0, 200.0);
  std::mt19937 rng(40);
  std::uniform_real_distribution<double> post(2, 61), radius(0, 400);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> track;
    for (int k = 0; k < 7; ++k) track.emplace_back(t.x_of(post(rng)), t.y_of(post(rng)), 500.0);
    const TrackGround g(t, track.data(), static_cast<int>(track.size()));
    const double r = radius(rng);
    double covered_to = 0;
    for (int s = 0; s + 1 < static_cast<int>(track.size()); ++s) {
      const TrackGround::Stretch h = g.held_stretch(s, s + 1, r);
      EXPECT_DOUBLE_EQ(h.to_m, g.at_vertex_m(s + 1) - r);
      if (h.empty()) {
        EXPECT_LE(g.at_vertex_m(s + 1) - r, 0.0) << "leg " << s << " radius " << r;
        continue;
      }
      EXPECT_NEAR(h.from_m, covered_to, 1e-9) << "leg " << s;
      covered_to = h.to_m;
      const double lower = std::min(track[static_cast<std::size_t>(s)].z(), track[static_cast<std::size_t>(s + 1)].z());
      // descending: the lower height over all of it
      EXPECT_DOUBLE_EQ(g.held_clearance_m(s, s + 1, lower + 7, lower, r), lower - g.highest_m(h.from_m, h.to_m));
    }
    EXPECT_DOUBLE_EQ(covered_to, std::max(g.length_m() - r, 0.0));
  }
}

// A leg joining vertices apart (the one a thinning makes) is held over the
// stretch of the legs it replaces; a height that is not a number holds
// nothing, and a stretch wholly before the start asks nothing.
TEST(TrackGround, AHeldStretchSpansTheLegsItJoins) {
  fields::Heightfield t = fields::testing::blank(40, 5, 10.0, 0.0f);
  t.at(10, 2) = 40.0f;  // a mast at 90 m along
  std::vector<Vec3> track;
  for (int i = 1; i <= 38; i += 4) track.emplace_back(t.x_of(i), t.y_of(2), 80.0);  // 40 m legs
  const TrackGround g(t, track.data(), static_cast<int>(track.size()));
  const TrackGround::Stretch joined = g.held_stretch(3, 6, 50.0);
  EXPECT_DOUBLE_EQ(joined.from_m, 70.0);
  EXPECT_DOUBLE_EQ(joined.to_m, 190.0);
  EXPECT_DOUBLE_EQ(g.held_clearance_m(3, 6, 80.0, 60.0, 50.0), 20.0);  // the lower height over the mast
  EXPECT_DOUBLE_EQ(g.held_clearance_m(4, 6, 80.0, 60.0, 50.0), 60.0);  // from 110 m: past the mast
  // climbing, the start's height only up to the start (then the plan's):
  // from 10 m before a leg 10 m short of the mast, nothing of it
  EXPECT_DOUBLE_EQ(g.held_clearance_m(2, 6, 80.0, 60.0, 10.0), 20.0);
  EXPECT_DOUBLE_EQ(g.held_clearance_m(2, 6, 60.0, 80.0, 10.0), 60.0);
  EXPECT_TRUE(std::isnan(g.held_clearance_m(3, 6, NAN, 60.0, 50.0)));
  EXPECT_TRUE(std::isnan(g.held_clearance_m(3, 6, 80.0, NAN, 50.0)));
  EXPECT_TRUE(g.held_stretch(0, 1, 50.0).empty());  // 40 m from the start: taken before it
  EXPECT_TRUE(std::isinf(g.held_clearance_m(0, 1, -1e9, -1e9, 50.0)));
  const TrackGround::Stretch last = g.held_stretch(8, 9, 50.0);  // to 50 m before the end
  EXPECT_DOUBLE_EQ(last.from_m, 270.0);
  EXPECT_DOUBLE_EQ(last.to_m, 310.0);
}

}  // namespace
}  // namespace visvol::rt
