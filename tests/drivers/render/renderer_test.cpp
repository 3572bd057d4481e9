// The renderer on a real OSMesa context, checked by pixels: background, the
// colour bar's ends, terrain colour against F_p from the sampler, path pixels
// at the projected vertices, markers, the slice view, errors, PNG output, a
// second thread, and reference images compared with a tolerance.
#include "drivers/render/renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "drivers/render/png_encoder.hpp"
#include "drivers/render/thumbnail.hpp"
#include "fields/sampler.hpp"
#include "msg/samples.hpp"
#include "render_test_util.hpp"

namespace visvol::render {
namespace {

using testing::blue_fraction;
using testing::Rgb8;
using testing::rgb_at;

class RendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string(testing::build_prism_pack("render_suite"));
    Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(*path_);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    pack_ = new std::shared_ptr<const storage::Pack>(*pack);
    Result<storage::PackLevel> level = storage::PackLevel::open(*pack_, 0);
    ASSERT_TRUE(level.ok());
    level_ = new storage::PackLevel(std::move(*level));
    RendererConfig config;
    config.max_width_px = 320;
    config.max_height_px = 240;
    config.transfer = testing::red_blue();
    Result<std::unique_ptr<Renderer>> r = Renderer::create(*pack_, config);
    ASSERT_TRUE(r.ok()) << r.status().message();
    renderer_ = r->release();
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete level_;
    delete pack_;
    std::remove(path_->c_str());
    delete path_;
  }

  static fields::FieldSampler<storage::PackLevel> sampler() {
    return fields::FieldSampler<storage::PackLevel>(*level_);
  }
  static const fields::VolumeGeometry& geometry() { return level_->geometry(); }
  static double fp_max() { return renderer_->scene_info().fp_max; }

  // A loop around the terrain's middle, `height_m` above the datum, F_p
  // rising from 0 to fp_max along it (so each vertex has its own colour).
  static std::vector<PathPoint> loop_path(double height_m, int vertices = 33) {
    const fields::VolumeGeometry& g = geometry();
    const double cx = g.origin_x + (g.nx - 1) * g.spacing_m / 2, cy = g.origin_y - (g.ny - 1) * g.spacing_m / 2;
    const double r = 0.3 * (g.nx - 1) * g.spacing_m;
    std::vector<PathPoint> p;
    for (int i = 0; i < vertices; ++i) {
      const double t = static_cast<double>(i) / (vertices - 1);
      const double a = 5.5 * t;  // not quite a full turn: the ends stay apart
      p.push_back({cx + r * std::cos(a), cy + r * std::sin(a), height_m, t * fp_max()});
    }
    return p;
  }

  static Frame frame_of(View view, int w, int h, const std::vector<PathPoint>* path = nullptr) {
    Frame f;
    f.view = view;
    f.width_px = w;
    f.height_px = h;
    if (path != nullptr) {
      f.path = path->data();
      f.path_size = path->size();
    }
    return f;
  }

  static std::string* path_;
  static std::shared_ptr<const storage::Pack>* pack_;
  static storage::PackLevel* level_;
  static Renderer* renderer_;
};
std::string* RendererTest::path_ = nullptr;
std::shared_ptr<const storage::Pack>* RendererTest::pack_ = nullptr;
storage::PackLevel* RendererTest::level_ = nullptr;
Renderer* RendererTest::renderer_ = nullptr;

TEST_F(RendererTest, BackgroundAndTheColourBarsEnds) {
  ASSERT_TRUE(renderer_->render(frame_of(View::top, 320, 240)).ok());
  const Image im = renderer_->image();
  ASSERT_EQ(im.width_px, 320);
  ASSERT_EQ(im.height_px, 240);
  const float* bg = renderer_->config().background_rgb;
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{319, 0}, std::pair{0, 239}, std::pair{319, 239}}) {
    const Rgb8 c = rgb_at(im, x, y);
    EXPECT_NEAR(c.r, bg[0] * 255, 1.0) << x << ", " << y;
    EXPECT_NEAR(c.g, bg[1] * 255, 1.0);
    EXPECT_NEAR(c.b, bg[2] * 255, 1.0);
  }
  // the bar: F = 1 (pure blue in this map) on top, F = 0 (pure red) at the bottom, linear between
  const PixelRect& bar = renderer_->layout().colour_bar;
  const double x = bar.x + bar.width / 2.0;
  const Rgb8 top = rgb_at(im, x, bar.y), bottom = rgb_at(im, x, bar.y + bar.height - 1);
  EXPECT_LE(top.r, 3);
  EXPECT_LE(top.g, 1);
  EXPECT_GE(top.b, 252);
  EXPECT_GE(bottom.r, 252);
  EXPECT_LE(bottom.g, 1);
  EXPECT_LE(bottom.b, 3);
  for (int row = 0; row < bar.height; row += 7) {
    const double expected = 1.0 - (row + 0.5) / bar.height;
    EXPECT_NEAR(blue_fraction(rgb_at(im, x, bar.y + row)), expected, 0.02) << "bar row " << row;
  }
}

TEST_F(RendererTest, TerrainIsColouredByFpAtTheChosenHeight) {
  Frame f = frame_of(View::top, 320, 240);
  f.height_above_ground_m = 25.0;
  ASSERT_TRUE(renderer_->render(f).ok());
  const Image im = renderer_->image();
  const auto s = sampler();
  const fields::VolumeGeometry& g = geometry();
  std::vector<double> errors;
  for (int j = 4; j < g.ny - 4; j += 5) {
    for (int i = 4; i < g.nx - 4; i += 5) {
      const double x = g.origin_x + i * g.spacing_m, y = g.origin_y - j * g.spacing_m;
      const double ground = s.height(x, y);
      const std::optional<PixelPoint> p = renderer_->project(x, y, ground);
      ASSERT_TRUE(p.has_value());
      const double expected = std::min(s.visibility(x, y, ground + 25.0) / fp_max(), 1.0);
      errors.push_back(std::fabs(blue_fraction(rgb_at(im, p->x, p->y)) - expected));
    }
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.02);       // median
  EXPECT_LT(errors[errors.size() * 9 / 10], 0.06);  // 90th percentile (steep spots near the ridges)
}

TEST_F(RendererTest, TerrainAboveThePathsAltitudeIsGreyBelowItColoured) {
  // a path 30 m up: the 60 m ridges rise through that height
  const std::vector<PathPoint> path = loop_path(30.0);
  ASSERT_TRUE(renderer_->render(frame_of(View::top, 320, 240, &path)).ok());
  const Image im = renderer_->image();
  const fields::VolumeGeometry& g = geometry();
  const auto s = sampler();
  // the ridge line of the first prism (two_prisms: i = 0.38 n) at the northern end
  const double ridge_x = g.origin_x + std::round(0.38 * 64) * g.spacing_m, ridge_y = g.origin_y - 12 * g.spacing_m;
  const Rgb8 ridge = rgb_at(im, renderer_->project(ridge_x, ridge_y, s.height(ridge_x, ridge_y))->x,
                            renderer_->project(ridge_x, ridge_y, s.height(ridge_x, ridge_y))->y);
  EXPECT_GT(s.height(ridge_x, ridge_y), 30.0);
  EXPECT_GT(ridge.g, 40);  // grey: green as strong as red and blue, which the F_p map never has
  EXPECT_NEAR(ridge.r, ridge.g, 12);
  EXPECT_NEAR(ridge.b, ridge.g, 12);
  // flat ground near the west edge: F_p at 30 m above the datum
  const double x = g.origin_x + 3 * g.spacing_m, y = g.origin_y - 32 * g.spacing_m;
  const std::optional<PixelPoint> p = renderer_->project(x, y, s.height(x, y));
  const Rgb8 flat = rgb_at(im, p->x, p->y);
  EXPECT_LE(flat.g, 2);
  EXPECT_NEAR(blue_fraction(flat), std::min(s.visibility(x, y, 30.0) / fp_max(), 1.0), 0.05);
}

// For every vertex away from the end markers: the pixel it projects to has
// the vertex's F_p colour, and the reversed colour when the path's F_p is
// reversed (terrain under it could match one colour, never both).
void expect_path_pixels(Renderer& r, const Frame& frame, const std::vector<PathPoint>& path, double fp_max) {
  std::vector<PathPoint> reversed = path;
  for (PathPoint& p : reversed) p.fp = fp_max - p.fp;
  Frame other = frame;
  other.path = reversed.data();
  ASSERT_TRUE(r.render(other).ok());
  const Image first = r.image();
  const std::vector<std::uint8_t> reversed_pixels(
      first.rgba, first.rgba + first.stride_bytes * static_cast<std::size_t>(first.height_px));
  ASSERT_TRUE(r.render(frame).ok());
  const Image im = r.image();
  const PixelPoint start = *r.project(path.front().x_m, path.front().y_m, path.front().z_m);
  const PixelPoint end = *r.project(path.back().x_m, path.back().y_m, path.back().z_m);
  int checked = 0;
  for (std::size_t i = 1; i + 1 < path.size(); ++i) {
    const std::optional<PixelPoint> p = r.project(path[i].x_m, path[i].y_m, path[i].z_m);
    ASSERT_TRUE(p.has_value());
    if (std::hypot(p->x - start.x, p->y - start.y) < 12 || std::hypot(p->x - end.x, p->y - end.y) < 12) continue;
    ASSERT_GE(p->x, 0);
    ASSERT_LT(p->x, im.width_px);
    ++checked;
    const Rgb8 c = rgb_at(im, p->x, p->y);
    const std::uint8_t* b =
        reversed_pixels.data() + static_cast<std::size_t>(p->y) * im.stride_bytes + static_cast<std::size_t>(p->x) * 4;
    const Rgb8 rc{b[0], b[1], b[2]};
    const std::string where =
        "vertex " + std::to_string(i) + " at " + std::to_string(p->x) + ", " + std::to_string(p->y);
    EXPECT_LE(c.g, 3) << where;
    EXPECT_GT(c.r + c.b, 60) << where;  // lit, not the dark outline
    EXPECT_NEAR(blue_fraction(c), path[i].fp / fp_max, 0.05) << where;
    EXPECT_NEAR(blue_fraction(rc), 1.0 - path[i].fp / fp_max, 0.05) << where << " (reversed)";
  }
  EXPECT_GE(checked, static_cast<int>(path.size()) / 2);
}

TEST_F(RendererTest, PathPixelsSitAtTheProjectedVerticesInTheirColour) {
  const std::vector<PathPoint> path = loop_path(120.0);
  for (View v : {View::top, View::oblique, View::volume}) {
    SCOPED_TRACE(to_string(v));
    Frame f = frame_of(v, 320, 240, &path);
    f.height_above_ground_m = 10.0;
    expect_path_pixels(*renderer_, f, path, fp_max());
  }
}

TEST_F(RendererTest, MarkersShowStartEndAndTheConstraintPoints) {
  const std::vector<PathPoint> path = loop_path(120.0);
  const fields::VolumeGeometry& g = geometry();
  const Marker markers[2] = {
      {MarkerKind::hidden_from, g.origin_x + 10 * g.spacing_m, g.origin_y - 50 * g.spacing_m, 20.0},
      {MarkerKind::visible_to, g.origin_x + 50 * g.spacing_m, g.origin_y - 54 * g.spacing_m, 20.0}};
  for (View v : {View::top, View::oblique}) {
    SCOPED_TRACE(to_string(v));
    Frame f = frame_of(v, 320, 240, &path);
    f.markers = markers;
    f.marker_count = 2;
    ASSERT_TRUE(renderer_->render(f).ok());
    const Image im = renderer_->image();
    const auto at = [&](double x, double y, double z) {
      const PixelPoint p = *renderer_->project(x, y, z);
      return rgb_at(im, p.x, p.y);
    };
    const Rgb8 start = at(path.front().x_m, path.front().y_m, path.front().z_m);
    EXPECT_GT(start.g, 150);  // green
    EXPECT_LT(start.r, 60);
    const Rgb8 end = at(path.back().x_m, path.back().y_m, path.back().z_m);
    EXPECT_GT(std::min({end.r, end.g, end.b}), 230);  // white
    const Rgb8 hidden = at(markers[0].x_m, markers[0].y_m, markers[0].z_m);
    EXPECT_LT(std::max({hidden.r, hidden.g, hidden.b}), 15);  // black
    const Rgb8 visible = at(markers[1].x_m, markers[1].y_m, markers[1].z_m);
    EXPECT_GT(visible.r, 200);  // magenta
    EXPECT_LT(visible.g, 70);
    EXPECT_GT(visible.b, 180);
  }
}

TEST_F(RendererTest, ScaleBarAgreesWithTheProjection) {
  ASSERT_TRUE(renderer_->render(frame_of(View::top, 320, 240)).ok());
  const fields::VolumeGeometry& g = geometry();
  const PixelPoint a = *renderer_->project(g.origin_x, g.origin_y, 0);
  const PixelPoint b = *renderer_->project(g.origin_x + 300, g.origin_y, 0);
  const FrameLayout& l = renderer_->layout();
  EXPECT_NEAR(l.metres_per_px, 300 / (b.x - a.x), 1e-6);
  // a 1, 2 or 5 x 10^k length, at most 30% of the scene's width
  const double decade = std::pow(10, std::floor(std::log10(l.scale_bar_m)));
  const double mantissa = l.scale_bar_m / decade;
  EXPECT_TRUE(std::fabs(mantissa - 1) < 1e-9 || std::fabs(mantissa - 2) < 1e-9 || std::fabs(mantissa - 5) < 1e-9)
      << l.scale_bar_m;
  EXPECT_LE(l.scale_bar_m / l.metres_per_px, 0.3 * l.scene.width + 1e-9);
  EXPECT_GT(l.scale_bar_m / l.metres_per_px, 0.3 * l.scene.width / 2.5);
  EXPECT_EQ(l.overlay_vertices_dropped, 0u);
}

TEST_F(RendererTest, SliceShowsGroundFieldAndPathAlongThePath) {
  // west to east across both prisms, 100 m up, F_p of each vertex as the field has it
  const fields::VolumeGeometry& g = geometry();
  const auto s = sampler();
  const double y = g.origin_y - 32 * g.spacing_m;
  std::vector<PathPoint> path;
  for (int i = 0; i <= 20; ++i) {
    const double x = g.origin_x + (4 + 2.75 * i) * g.spacing_m;
    path.push_back({x, y, 100.0, s.visibility(x, y, 100.0)});
  }
  ASSERT_TRUE(renderer_->render(frame_of(View::slice, 320, 240, &path)).ok());
  const Image im = renderer_->image();
  const PixelRect& panel = renderer_->layout().scene;
  EXPECT_FALSE(renderer_->project(path[0].x_m, path[0].y_m, 100).has_value());
  const double length = path.back().x_m - path.front().x_m;
  // the panel's bottom row is ground all along
  for (int c = 10; c < panel.width - 40; c += 23) {
    const Rgb8 ground = rgb_at(im, panel.x + c, panel.y + panel.height - 1);
    EXPECT_NEAR(ground.r, 0.45 * 255, 3) << "column " << c;
    EXPECT_NEAR(ground.g, 0.38 * 255, 3);
    EXPECT_NEAR(ground.b, 0.31 * 255, 3);
  }
  // the ridge of the first prism: ground up to 60 m there, field above
  const double ridge_x = g.origin_x + std::round(0.38 * 64) * g.spacing_m;
  const double d = ridge_x - path.front().x_m;
  const Rgb8 under = rgb_at(im, renderer_->slice_pixel(d, 40.0)->x, renderer_->slice_pixel(d, 40.0)->y);
  EXPECT_NEAR(under.g, 0.38 * 255, 3);
  for (double z : {75.0, 130.0, 170.0}) {
    const PixelPoint p = *renderer_->slice_pixel(d, z);
    const Rgb8 c = rgb_at(im, p.x, p.y);
    EXPECT_LE(c.g, 2) << z;
    EXPECT_NEAR(blue_fraction(c), std::min(s.visibility(ridge_x, y, z) / fp_max(), 1.0), 0.06) << "height " << z;
  }
  // the path line is drawn in each vertex's colour
  for (std::size_t i = 2; i + 2 < path.size(); i += 3) {
    const PixelPoint p = *renderer_->slice_pixel(path[i].x_m - path.front().x_m, path[i].z_m);
    const Rgb8 c = rgb_at(im, p.x, p.y);
    EXPECT_NEAR(blue_fraction(c), path[i].fp / fp_max(), 0.03) << "vertex " << i;
  }
  EXPECT_NEAR(renderer_->slice_pixel(length, 100.0)->x, panel.x + panel.width, 1e-9);
}

TEST_F(RendererTest, FramesAreCheckedAndErrorsNameTheField) {
  const std::vector<PathPoint> path = loop_path(100.0);
  std::vector<PathPoint> bad_fp = path, bad_xyz = path;
  bad_fp[7].fp = 1.5;
  bad_xyz[3].z_m = std::nan("");
  const std::vector<PathPoint> one(path.begin(), path.begin() + 1);
  std::vector<PathPoint> vertical(2, path[0]);
  vertical[1].z_m += 50;
  const std::vector<PathPoint> too_many(kDefaultMaxPathVertices + 1, path[0]);
  const Marker nan_marker[1] = {{MarkerKind::visible_to, 0, std::nan(""), 0}};
  struct Case {
    Frame frame;
    const char* expected;
  };
  std::vector<Case> cases;
  cases.push_back({frame_of(View::top, 321, 240), "frame size 321 x 240 is outside 32..320 x 32..240"});
  cases.push_back({frame_of(View::top, 16, 240), "frame size 16 x 240"});
  cases.push_back({frame_of(View::top, 100, 100, &bad_fp), "path vertex 7: F_p 1.5"});
  cases.push_back({frame_of(View::top, 100, 100, &bad_xyz), "path vertex 3: position is not finite"});
  cases.push_back({frame_of(View::top, 100, 100, &one), "path of 1 vertices: need 0 or 2..512"});
  cases.push_back({frame_of(View::top, 100, 100, &too_many), "path of 513 vertices"});
  cases.push_back({frame_of(View::slice, 100, 100), "the slice view needs a path"});
  cases.push_back({frame_of(View::slice, 100, 100, &vertical), "the slice view needs a path that moves horizontally"});
  Frame markers = frame_of(View::top, 100, 100);
  markers.markers = nan_marker;
  markers.marker_count = 1;
  cases.push_back({markers, "marker 0: position is not finite"});
  markers.marker_count = 17;
  cases.push_back({markers, "17 markers: at most 16"});
  Frame height = frame_of(View::top, 100, 100);
  height.height_above_ground_m = -3.0;
  cases.push_back({height, "height above ground -3"});
  // a good frame first, so the failures must leave its picture alone
  ASSERT_TRUE(renderer_->render(frame_of(View::top, 100, 80)).ok());
  for (const Case& c : cases) {
    const Status s = renderer_->render(c.frame);
    ASSERT_FALSE(s.ok()) << c.expected;
    EXPECT_EQ(s.code(), Errc::invalid_argument);
    EXPECT_NE(s.message().find(c.expected), std::string::npos) << "got: " << s.message();
  }
  EXPECT_EQ(renderer_->image().width_px, 100);
  EXPECT_EQ(renderer_->image().height_px, 80);
}

TEST_F(RendererTest, CreateChecksItsConfiguration) {
  RendererConfig c;
  c.max_width_px = 5000;
  EXPECT_NE(Renderer::create(*pack_, c).status().message().find("renderer size 5000 x 768"), std::string::npos);
  c = RendererConfig{};
  c.fp_max = 2;
  EXPECT_NE(Renderer::create(*pack_, c).status().message().find("fp_max 2"), std::string::npos);
  c = RendererConfig{};
  c.png_compression_level = 12;
  EXPECT_NE(Renderer::create(*pack_, c).status().message().find("compression level 12"), std::string::npos);
  c = RendererConfig{};
  c.transfer.opacity.clear();
  EXPECT_NE(Renderer::create(*pack_, c).status().message().find("no opacity points"), std::string::npos);
  c = RendererConfig{};
  c.vertical_exaggeration = -1;
  EXPECT_FALSE(Renderer::create(*pack_, c).ok());
  EXPECT_FALSE(Renderer::create(nullptr, RendererConfig{}).ok());
}

TEST_F(RendererTest, PngOfTheFrameDecodesToItsPixelsAndFitsAThumbnailSample) {
  const std::vector<PathPoint> path = loop_path(100.0);
  ASSERT_TRUE(renderer_->render(frame_of(View::oblique, 256, 192, &path)).ok());
  auto sample = std::make_unique<msg::ThumbnailSample>();
  Result<std::size_t> n = renderer_->encode_png(sample->png, sizeof sample->png);
  ASSERT_TRUE(n.ok()) << n.status().message();
  const testing::Decoded d = testing::decode_png(sample->png, *n);
  ASSERT_TRUE(d.error.empty()) << d.error;
  ASSERT_EQ(d.width, 256);
  ASSERT_EQ(d.height, 192);
  const Image im = renderer_->image();
  for (int y = 0; y < 192; ++y) {
    for (int x = 0; x < 256; ++x) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(
            d.rgb[(static_cast<std::size_t>(y) * 256 + static_cast<std::size_t>(x)) * 3 + static_cast<std::size_t>(c)],
            im.pixel(x, y)[c]);
      }
    }
  }
  Result<std::size_t> small = renderer_->encode_png(sample->png, 100);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.status().message().find("does not fit the 100-byte output buffer"), std::string::npos);
}

TEST_F(RendererTest, ThumbnailFromAPathSampleAsTheConsoleHandsItOver) {
  const std::vector<PathPoint> path = loop_path(100.0, 40);
  auto sample = std::make_unique<msg::PathSample>();
  sample->stamp_ns = 1234567;
  sample->vertex_count = static_cast<std::uint32_t>(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    sample->vertices[i] = {{path[i].x_m, path[i].y_m, path[i].z_m}, path[i].fp, 80.0};
  }
  auto thumbnail = std::make_unique<msg::ThumbnailSample>();
  auto scratch = std::make_unique<PathPoint[]>(msg::kMaxPathVertices);
  ASSERT_TRUE(render_thumbnail(*renderer_, *sample, frame_of(View::top, 240, 180), scratch.get(), *thumbnail).ok());
  EXPECT_EQ(thumbnail->stamp_ns, 1234567);
  const testing::Decoded d = testing::decode_png(thumbnail->png, thumbnail->png_size_bytes);
  ASSERT_TRUE(d.error.empty()) << d.error;
  EXPECT_EQ(d.width, 240);
  EXPECT_EQ(d.height, 180);
  // the path is in the picture: its middle vertex shows its own colour
  const PathPoint& mid = path[20];
  const PixelPoint p = *renderer_->project(mid.x_m, mid.y_m, mid.z_m);
  EXPECT_NEAR(blue_fraction(rgb_at(renderer_->image(), p.x, p.y)), mid.fp / fp_max(), 0.05);
  // a one-vertex sample is refused and not stamped
  sample->vertex_count = 1;
  sample->stamp_ns = 99;
  const Status s = render_thumbnail(*renderer_, *sample, frame_of(View::top, 240, 180), scratch.get(), *thumbnail);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(thumbnail->stamp_ns, 1234567);
}

TEST_F(RendererTest, RendersTheSameFromAnotherThread) {
  const std::vector<PathPoint> path = loop_path(100.0);
  const Frame f = frame_of(View::volume, 200, 150, &path);
  ASSERT_TRUE(renderer_->render(f).ok());
  const Image a = renderer_->image();
  const std::vector<std::uint8_t> here(a.rgba, a.rgba + a.stride_bytes * 150);
  Status there;
  std::thread worker([&] { there = renderer_->render(f); });
  worker.join();
  ASSERT_TRUE(there.ok()) << there.message();
  const Image b = renderer_->image();
  EXPECT_TRUE(std::equal(here.begin(), here.end(), b.rgba));
}

TEST_F(RendererTest, VolumeFogLiesInsideTheFieldAndOverTheTerrain) {
  // a second renderer (its own context, alternating with the suite's on this
  // thread): a green fog of constant opacity
  RendererConfig config;
  config.max_width_px = 200;
  config.max_height_px = 150;
  config.transfer = testing::red_blue();
  config.transfer.colour = {{0.0, 0.0, 1.0, 0.0}};
  config.transfer.opacity = {{0.0, 0.05}};
  Result<std::unique_ptr<Renderer>> fog = Renderer::create(*pack_, config);
  ASSERT_TRUE(fog.ok()) << fog.status().message();
  ASSERT_TRUE((*fog)->render(frame_of(View::volume, 200, 150)).ok());
  ASSERT_TRUE(renderer_->render(frame_of(View::volume, 200, 150)).ok());  // transparent
  const Image green = (*fog)->image(), clear = renderer_->image();
  const fields::VolumeGeometry& g = geometry();
  const auto s = sampler();
  // over the terrain's middle the fog is green on the grey terrain
  const double x = g.origin_x + 32 * g.spacing_m, y = g.origin_y - 32 * g.spacing_m;
  const PixelPoint p = *(*fog)->project(x, y, s.height(x, y));
  const Rgb8 fogged = rgb_at(green, p.x, p.y), bare = rgb_at(clear, p.x, p.y);
  EXPECT_GT(fogged.g, bare.g + 40);
  EXPECT_LT(fogged.r, bare.r);
  EXPECT_NEAR(bare.r, bare.g, 12);  // the terrain alone is grey in the volume view
  // outside the field's block the background is untouched
  const Rgb8 corner = rgb_at(green, 1, 1), corner_clear = rgb_at(clear, 1, 1);
  EXPECT_EQ(corner.r, corner_clear.r);
  EXPECT_EQ(corner.g, corner_clear.g);
  EXPECT_EQ(corner.b, corner_clear.b);
}

// Reference pictures (default colours, path and markers): per channel, 99% of
// pixels within 8 levels and a mean difference under 1.5, so another CPU's
// llvmpipe rounding passes and a changed picture does not. Set
// VISVOL_UPDATE_RENDER_REFERENCE=1 to rewrite them (then look at them).
void compare_with_reference(Renderer& r, const std::string& name) {
  const std::string file = std::string(VISVOL_TEST_DATA) + "/render/" + name;
  std::vector<std::uint8_t> png(PngEncoder::worst_case_bytes(256, 192));
  Result<std::size_t> n = r.encode_png(png.data(), png.size());
  ASSERT_TRUE(n.ok()) << n.status().message();
  const char* update = std::getenv("VISVOL_UPDATE_RENDER_REFERENCE");
  if (update != nullptr && std::string(update) == "1") {
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(*n));
    GTEST_SKIP() << "rewrote " << file;
  }
  const std::vector<std::uint8_t> bytes = testing::read_file(file);
  ASSERT_FALSE(bytes.empty()) << file << " is missing";
  const testing::Decoded ref = testing::decode_png(bytes.data(), bytes.size());
  ASSERT_TRUE(ref.error.empty()) << ref.error;
  const Image im = r.image();
  ASSERT_EQ(ref.width, im.width_px);
  ASSERT_EQ(ref.height, im.height_px);
  std::size_t far = 0;
  double sum = 0;
  for (int y = 0; y < im.height_px; ++y) {
    for (int x = 0; x < im.width_px; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int diff =
            std::abs(im.pixel(x, y)[c] - ref.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(im.width_px) +
                                                  static_cast<std::size_t>(x)) *
                                                     3 +
                                                 static_cast<std::size_t>(c)]);
        far += diff > 8;
        sum += diff;
      }
    }
  }
  const double values = 3.0 * im.width_px * im.height_px;
  EXPECT_LT(static_cast<double>(far) / values, 0.01) << name << ": " << far << " values differ by more than 8";
  EXPECT_LT(sum / values, 1.5) << name;
}

TEST_F(RendererTest, MatchesTheReferencePictures) {
  RendererConfig config;  // default colours, the shipped look
  config.max_width_px = 256;
  config.max_height_px = 192;
  Result<std::unique_ptr<Renderer>> r = Renderer::create(*pack_, config);
  ASSERT_TRUE(r.ok()) << r.status().message();
  std::vector<PathPoint> path = loop_path(90.0);
  const auto s = sampler();
  for (PathPoint& p : path) p.fp = s.visibility(p.x_m, p.y_m, p.z_m);
  const fields::VolumeGeometry& g = geometry();
  const Marker markers[2] = {
      {MarkerKind::hidden_from, g.origin_x + 10 * g.spacing_m, g.origin_y - 50 * g.spacing_m, 20.0},
      {MarkerKind::visible_to, g.origin_x + 50 * g.spacing_m, g.origin_y - 54 * g.spacing_m, 20.0}};
  for (View v : {View::oblique, View::volume}) {
    SCOPED_TRACE(to_string(v));
    Frame f = frame_of(v, 256, 192, &path);
    f.markers = markers;
    f.marker_count = 2;
    ASSERT_TRUE((*r)->render(f).ok());
    compare_with_reference(**r, std::string("two_prisms_") + to_string(v) + ".png");
  }
}

}  // namespace
}  // namespace visvol::render
