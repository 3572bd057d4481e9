#include "drivers/render/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "drivers/render/overlay.hpp"

namespace visvol::render::detail {
namespace {

Box test_box() {
  Box b;
  b.min = Vec3(-500, -300, 0);
  b.max = Vec3(500, 300, 100);
  return b;
}

std::array<Vec3, 8> corners_of(const Box& b) {
  std::array<Vec3, 8> c;
  for (int n = 0; n < 8; ++n) {
    c[static_cast<std::size_t>(n)] =
        Vec3((n & 1) ? b.max.x() : b.min.x(), (n & 2) ? b.max.y() : b.min.y(), (n & 4) ? b.max.z() : b.min.z());
  }
  return c;
}

// Every corner inside the viewport, and the box spanning most of it one way.
void expect_fitted(const Camera& cam, const Box& box, const PixelRect& vp) {
  double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
  for (const Vec3& c : corners_of(box)) {
    const std::optional<PixelPoint> p = cam.project(c);
    ASSERT_TRUE(p.has_value());
    EXPECT_GE(p->x, vp.x);
    EXPECT_LE(p->x, vp.x + vp.width);
    EXPECT_GE(p->y, vp.y);
    EXPECT_LE(p->y, vp.y + vp.height);
    lo_x = std::min(lo_x, p->x);
    hi_x = std::max(hi_x, p->x);
    lo_y = std::min(lo_y, p->y);
    hi_y = std::max(hi_y, p->y);
  }
  const double fill = std::max((hi_x - lo_x) / vp.width, (hi_y - lo_y) / vp.height);
  EXPECT_GT(fill, 0.9);
  EXPECT_NEAR((lo_x + hi_x) / 2, vp.x + vp.width / 2.0, 1.0);  // centred
  EXPECT_NEAR((lo_y + hi_y) / 2, vp.y + vp.height / 2.0, 1.0);
}

TEST(Camera, TopViewFitsTheBoxNorthUpEastRightAtOneScale) {
  const PixelRect vp{10, 20, 300, 200};
  const Box box = test_box();
  const Camera cam = top_camera(box, vp);
  expect_fitted(cam, box, vp);
  const PixelPoint c = *cam.project(Vec3(0, 0, 0));
  const PixelPoint north = *cam.project(Vec3(0, 100, 0));
  const PixelPoint east = *cam.project(Vec3(100, 0, 0));
  EXPECT_NEAR(north.x, c.x, 1e-6);
  EXPECT_LT(north.y, c.y);  // rows run down: north is up
  EXPECT_GT(east.x, c.x);
  EXPECT_NEAR(east.y, c.y, 1e-6);
  EXPECT_NEAR(c.y - north.y, east.x - c.x, 1e-6);  // square pixels
  // heights do not move a point in the top view
  const PixelPoint high = *cam.project(Vec3(0, 0, 90));
  EXPECT_NEAR(high.x, c.x, 1e-6);
  EXPECT_NEAR(high.y, c.y, 1e-6);
}

TEST(Camera, ObliqueViewFitsTheBoxLooksNorthAndShowsHeight) {
  const PixelRect vp{0, 0, 400, 300};
  const Box box = test_box();
  const Camera cam = oblique_camera(box, vp);
  EXPECT_TRUE(cam.perspective);
  expect_fitted(cam, box, vp);
  const PixelPoint c = *cam.project(Vec3(0, 0, 0));
  EXPECT_LT(cam.project(Vec3(0, 200, 0))->y, c.y);  // north is away from the viewer: up
  EXPECT_LT(cam.project(Vec3(0, 0, 80))->y, c.y);   // up is up
  EXPECT_LT(cam.eye.y(), 0.0);                      // from the south
  EXPECT_LT(cam.eye.x(), 0.0);                      // and a little west
  // behind the camera there is no pixel
  const Vec3 behind = cam.eye + (cam.eye - Vec3(0, 0, 0));
  EXPECT_FALSE(cam.project(behind).has_value());
  // the inverse undoes the projection
  const Eigen::Vector4d clip = cam.view_proj * Vec3(120, -40, 30).homogeneous();
  const Eigen::Vector4d back = cam.inverse * clip;
  EXPECT_NEAR(back.x() / back.w(), 120, 1e-6);
  EXPECT_NEAR(back.z() / back.w(), 30, 1e-6);
}

TEST(Layout, SceneAndColourBarSitApartInsideTheImage) {
  for (const auto& [w, h] : {std::pair{256, 256}, std::pair{1024, 768}, std::pair{32, 32}, std::pair{4096, 200}}) {
    const BaseLayout b = base_layout(w, h);
    const FrameLayout& l = b.layout;
    EXPECT_GE(l.scene.x, 0);
    EXPECT_GE(l.scene.y, 0);
    EXPECT_LE(l.scene.x + l.scene.width, l.colour_bar.x) << w << "x" << h;
    EXPECT_LE(l.colour_bar.x + l.colour_bar.width, w);
    EXPECT_LE(l.scene.y + l.scene.height, h);
    EXPECT_GT(l.colour_bar.y, 0);  // room for its title
    EXPECT_LE(l.colour_bar.y + l.colour_bar.height, h);
    EXPECT_GT(l.colour_bar.height, 0);
    EXPECT_GE(b.text_scale, 1);
  }
}

TEST(Scale, NiceLengthsAndTheirLabels) {
  EXPECT_DOUBLE_EQ(nice_length_m(0.3), 0.2);
  EXPECT_DOUBLE_EQ(nice_length_m(7), 5);
  EXPECT_DOUBLE_EQ(nice_length_m(10), 10);
  EXPECT_DOUBLE_EQ(nice_length_m(1999), 1000);
  EXPECT_DOUBLE_EQ(nice_length_m(2000), 2000);
  EXPECT_DOUBLE_EQ(nice_length_m(0), 0);
  char text[16];
  length_label(500, text, sizeof text);
  EXPECT_STREQ(text, "500 m");
  length_label(2000, text, sizeof text);
  EXPECT_STREQ(text, "2 km");
  length_label(0.5, text, sizeof text);
  EXPECT_STREQ(text, "0.5 m");
}

TEST(TerrainMesh, SamplesEveryStepKeepsTheEdgesAndHasUpwardNormals) {
  EXPECT_EQ(mesh_samples(10, 4), (std::vector<int>{0, 4, 8, 9}));
  EXPECT_EQ(mesh_samples(9, 4), (std::vector<int>{0, 4, 8}));
  EXPECT_EQ(mesh_samples(5, 1), (std::vector<int>{0, 1, 2, 3, 4}));
  // a plane rising 0.1 m per metre eastward, 10 m posts
  const int nx = 9, ny = 6;
  std::vector<float> h(static_cast<std::size_t>(nx * ny));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) h[static_cast<std::size_t>(j * nx + i)] = static_cast<float>(100 + i);
  }
  SceneFrame frame;
  frame.centre_x_m = 1000;
  frame.centre_y_m = 5000;
  frame.z_ref_m = 90;
  frame.exaggeration = 2;
  const TerrainMesh m = terrain_mesh(h, nx, ny, 2, 10.0, 960.0, 5025.0, frame, 0.0);
  EXPECT_EQ(m.nx, 5);  // 0 2 4 6 8
  EXPECT_EQ(m.ny, 4);  // 0 2 4 5
  const std::size_t surface = static_cast<std::size_t>(m.nx * m.ny);
  const std::size_t skirt = 2 * 2 * static_cast<std::size_t>(m.nx + m.ny);
  ASSERT_EQ(m.vertices.size(), (surface + skirt) * kTerrainFloats);
  EXPECT_EQ(m.indices.size(),
            static_cast<std::size_t>((m.nx - 1) * (m.ny - 1) * 6 + 2 * (m.nx - 1) * 6 + 2 * (m.ny - 1) * 6));
  for (std::uint32_t i : m.indices) EXPECT_LT(i, surface + skirt);
  // surface: scene position of post (2, 2) and the tilted normal (slope 0.2 after exaggeration)
  const float* v = &m.vertices[(1 * static_cast<std::size_t>(m.nx) + 1) * kTerrainFloats];
  EXPECT_FLOAT_EQ(v[0], 960 + 20 - 1000);
  EXPECT_FLOAT_EQ(v[1], 5025 - 20 - 5000);
  EXPECT_FLOAT_EQ(v[2], (102 - 90) * 2);
  const Vec3 n(v[3], v[4], v[5]);
  EXPECT_NEAR(n.norm(), 1.0, 1e-6);
  EXPECT_NEAR(n.x() / n.z(), -0.2, 1e-6);
  EXPECT_NEAR(n.y(), 0.0, 1e-6);
  EXPECT_EQ(v[6], 0.0f);
  // skirt: flagged, reaching down to the bottom
  const float* s = &m.vertices[(surface + 1) * kTerrainFloats];
  EXPECT_EQ(s[6], 1.0f);
  EXPECT_EQ(s[2], 0.0f);
}

TEST(TerrainMesh, StridesGrowByAboutHalfUntilTheMeshIsTooCoarse) {
  EXPECT_EQ(mesh_steps(1, 466), (std::vector<int>{1, 2, 3, 5, 8, 12, 18, 27, 41}));
  EXPECT_EQ(mesh_steps(3, 466), (std::vector<int>{3, 5, 8, 12, 18, 27, 41}));
  EXPECT_EQ(mesh_steps(0, 4), (std::vector<int>{1}));  // a tiny terrain: the finest only
  EXPECT_EQ(mesh_steps(1, 100000).size(), static_cast<std::size_t>(kMaxMeshes));
  // with these, a 230-pixel picture of the 466-post SF North terrain gets a
  // vertex every 1.5 pixels (stride 3), not every pixel (stride 2 of 1, 2, 4, 8)
  EXPECT_EQ(choose_mesh_step(mesh_steps(1, 466), 230.0 / 466), 3);
}

TEST(TerrainMesh, ChoosesAboutOneVertexPerTwoPixels) {
  const std::vector<int> steps = {1, 2, 4, 8};
  EXPECT_EQ(choose_mesh_step(steps, 0.25), 8);  // 4 posts a pixel: a vertex every 2 pixels
  EXPECT_EQ(choose_mesh_step(steps, 0.5), 4);
  EXPECT_EQ(choose_mesh_step(steps, 0.3), 4);       // 6.7 posts per 2 pixels: not 8
  EXPECT_EQ(choose_mesh_step(steps, 2.0), 1);       // magnified: every post
  EXPECT_EQ(choose_mesh_step({2, 4}, 10.0), 2);     // never finer than prepared
  EXPECT_EQ(choose_mesh_step(steps, 0.0), 1);       // no scale known: the finest
  EXPECT_EQ(choose_mesh_step(steps, 0.5, 4.0), 8);  // a vertex per 4 x 4 pixels
}

TEST(Tube, RingsAreRoundAroundThePathAndIndexedBetweenRings) {
  const Vec3 centres[3] = {Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(20, 5, 3)};
  const float fp[3] = {0.1f, 0.5f, 0.9f};
  std::vector<float> out(3 * kTubeSides * kTubeFloats);
  tube_vertices(centres, fp, 3, 2.0, out.data());
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < kTubeSides; ++k) {
      const float* v = &out[static_cast<std::size_t>((i * kTubeSides + k) * kTubeFloats)];
      const Vec3 p(v[0], v[1], v[2]), n(v[3], v[4], v[5]);
      EXPECT_NEAR((p - centres[i]).norm(), 2.0, 1e-5);
      EXPECT_NEAR(n.norm(), 1.0, 1e-5);
      EXPECT_NEAR((p - centres[i]).normalized().dot(n), 1.0, 1e-5);
      EXPECT_FLOAT_EQ(v[6], fp[i]);
    }
  }
  // the first ring is perpendicular to the first segment
  for (int k = 0; k < kTubeSides; ++k) EXPECT_NEAR(out[static_cast<std::size_t>(k * kTubeFloats + 3)], 0.0, 1e-6);
  const std::vector<std::uint32_t> idx = tube_indices(3);
  EXPECT_EQ(idx.size(), 2u * kTubeSides * 6);
  for (std::uint32_t i : idx) EXPECT_LT(i, 3u * kTubeSides);
}

TEST(Overlay, CountsWhatDoesNotFitAndDrawsKnownGlyphs) {
  std::vector<float> buffer(12 * kOverlayFloats);
  OverlayBuilder o(buffer.data(), 12);
  o.rect(0, 0, 10, 10, Rgba{1, 1, 1, 1});                  // 6
  o.line(0, 0, 10, 0, 2, Rgba{1, 0, 0, 1}, 0.25f, 0.75f);  // 6
  EXPECT_EQ(o.vertex_count(), 12u);
  EXPECT_EQ(o.dropped(), 0u);
  EXPECT_FLOAT_EQ(buffer[6 * kOverlayFloats + 6], 0.25f);  // the line's F_p colour
  o.disc(5, 5, 3, Rgba{0, 1, 0, 1});
  EXPECT_EQ(o.vertex_count(), 12u);
  EXPECT_GT(o.dropped(), 0u);
  for (char c : std::string("0123456789.- kmNFp")) EXPECT_NE(glyph_rows(c), nullptr) << c;
  EXPECT_EQ(glyph_rows('Q'), nullptr);
  EXPECT_DOUBLE_EQ(OverlayBuilder::text_width("2 km", 2), (4 * kGlyphAdvance - 1) * 2);
}

}  // namespace
}  // namespace visvol::render::detail
