#include "fields/viewshed.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "fields/gdal/dem_io.hpp"
#include "fields/hull_kernel.hpp"
#include "terrains.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

TEST(Viewshed, FlatGroundIsAllVisible) {
  const Heightfield hf = flat(30);
  ViewshedParams p;
  p.observer_x = hf.x_of(4);
  p.observer_y = hf.y_of(9);
  const Result<Viewshed> vs = compute_viewshed(hf, p);
  ASSERT_TRUE(vs.ok()) << vs.status().message();
  EXPECT_EQ(vs->observer_i, 4);
  EXPECT_EQ(vs->observer_j, 9);
  for (std::uint8_t v : vs->value) ASSERT_EQ(v, kViewshedVisible);
}

// A horizon reaches kMaxHullRing posts (16-bit stencil indices): a DEM
// longer than that from the observer is refused with the distance to give,
// never computed with wrapped indices; within it, computed.
TEST(Viewshed, ADemBeyondAHorizonsReachIsRefusedUnlessTheDistanceIsBounded) {
  Heightfield hf = flat(2);
  hf.nx = kMaxHullRing + 2;
  hf.height_m.assign(hf.size(), 10.0f);
  ViewshedParams p;
  p.observer_x = hf.x_of(0);
  p.observer_y = hf.y_of(0);
  p.exact_rings = 4;
  const Result<Viewshed> refused = compute_viewshed(hf, p);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("--max-distance"), std::string::npos) << refused.status().message();
  p.max_distance_m = 100 * hf.spacing_m;
  const Result<Viewshed> bounded = compute_viewshed(hf, p);
  ASSERT_TRUE(bounded.ok()) << bounded.status().message();
  EXPECT_EQ(bounded->value[50], kViewshedVisible);
  EXPECT_EQ(bounded->value[500], kViewshedOutside);
}

TEST(Viewshed, WallShadowsTheFarSide) {
  const Heightfield hf = wall(30, 15, 20.0f);
  ViewshedParams p;
  p.observer_x = hf.x_of(5);
  p.observer_y = hf.y_of(15);
  const Result<Viewshed> vs = compute_viewshed(hf, p);
  ASSERT_TRUE(vs.ok());
  EXPECT_EQ(vs->at(10, 15), kViewshedVisible);
  EXPECT_EQ(vs->at(15, 15), kViewshedVisible);  // the wall's top
  EXPECT_EQ(vs->at(20, 15), kViewshedHidden);
  EXPECT_EQ(vs->at(29, 15), kViewshedHidden);
}

TEST(Viewshed, MaxDistanceMarksOutsideCells) {
  const Heightfield hf = flat(30, 10.0);
  ViewshedParams p;
  p.observer_x = hf.x_of(15);
  p.observer_y = hf.y_of(15);
  p.max_distance_m = 50.0;
  const Result<Viewshed> vs = compute_viewshed(hf, p);
  ASSERT_TRUE(vs.ok());
  EXPECT_EQ(vs->at(18, 15), kViewshedVisible);
  EXPECT_EQ(vs->at(20, 15), kViewshedVisible);  // exactly 50 m
  EXPECT_EQ(vs->at(21, 15), kViewshedOutside);
  EXPECT_EQ(vs->at(19, 19), kViewshedOutside);  // 56.6 m
}

TEST(Viewshed, AHugeMaxDistanceIsRefusedAndALargeOneCoversTheDem) {
  // 1e308 m made a negative radius and an uncaught std::length_error (abort).
  const Heightfield hf = flat(30, 10.0);
  ViewshedParams p;
  p.observer_x = hf.x_of(15);
  p.observer_y = hf.y_of(15);
  p.max_distance_m = 1e308;
  const Result<Viewshed> refused = compute_viewshed(hf, p);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("max distance: 1e+308 m is outside 0..1e+08 m"), std::string::npos)
      << refused.status().message();
  p.max_distance_m = kMaxViewshedDistanceM;  // far beyond the grid: clamped to it
  const Result<Viewshed> vs = compute_viewshed(hf, p);
  ASSERT_TRUE(vs.ok()) << vs.status().message();
  for (std::uint8_t v : vs->value) ASSERT_EQ(v, kViewshedVisible);
}

TEST(Viewshed, RefusesObserverOutsideTheDem) {
  const Heightfield hf = flat(10);
  ViewshedParams p;
  p.observer_x = hf.x_of(-3);
  p.observer_y = hf.y_of(2);
  const Result<Viewshed> vs = compute_viewshed(hf, p);
  ASSERT_FALSE(vs.ok());
  EXPECT_NE(vs.status().message().find("outside the DEM"), std::string::npos);
  p.observer_x = std::nan("");
  EXPECT_FALSE(compute_viewshed(hf, p).ok());
}

// GRASS r.viewshed's own test case (shared/data, GPL: used by path).
struct GrassReference {
  int rows = 0, cols = 0;
  std::vector<bool> visible;
};

bool read_grass_reference(const std::string& path, GrassReference& ref) {
  std::ifstream in(path);
  if (!in) return false;
  std::string key;
  for (int n = 0; n < 6; ++n) {
    std::string value;
    in >> key >> value;
    if (key == "rows:") ref.rows = std::stoi(value);
    if (key == "cols:") ref.cols = std::stoi(value);
  }
  std::string token;
  while (in >> token) ref.visible.push_back(token != "*");
  return static_cast<int>(ref.visible.size()) == ref.rows * ref.cols;
}

TEST(Viewshed, AgreesWithGrassRviewshedReference) {
  const std::string dir = std::string(VISVOL_SHARED_DATA) + "/dem/grass_viewshed_reference";
  GrassReference ref;
  if (!read_grass_reference(dir + "/lake_viewshed.ascii", ref)) {
    GTEST_SKIP() << "GRASS reference not found under " << dir;
  }
  const Result<Heightfield> hf = read_heightfield(dir + "/elevation.ascii");
  ASSERT_TRUE(hf.ok()) << hf.status().message();
  ASSERT_EQ(hf->nx, ref.cols);
  ASSERT_EQ(hf->ny, ref.rows);
  ViewshedParams p;
  p.observer_x = 634720;
  p.observer_y = 216180;
  p.observer_height_m = 1.72;
  p.target_height_m = 0.0;
  const Result<Viewshed> vs = compute_viewshed(*hf, p);
  ASSERT_TRUE(vs.ok()) << vs.status().message();
  std::size_t agree = 0, visible_ours = 0, visible_ref = 0;
  for (std::size_t n = 0; n < ref.visible.size(); ++n) {
    const bool ours = vs->value[n] == kViewshedVisible;
    agree += ours == ref.visible[n];
    visible_ours += ours;
    visible_ref += ref.visible[n];
  }
  const double fraction = double(agree) / static_cast<double>(ref.visible.size());
  RecordProperty("agreement", std::to_string(fraction));
  std::cout << "r.viewshed reference: " << agree << " of " << ref.visible.size() << " cells agree (" << 100.0 * fraction
            << "%); visible ours " << visible_ours << ", GRASS " << visible_ref << "\n";
  EXPECT_GE(fraction, 0.99);
}

}  // namespace
}  // namespace visvol::fields
