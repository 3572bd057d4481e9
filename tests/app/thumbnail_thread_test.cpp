// The console's renderer thread: a thumbnail when the rope comes to rest, at
// most the configured rate, one last picture at stop, and its PNG on disk.
#include "app/thumbnail_thread.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

#include "../fields/terrains.hpp"
#include "storage/pack_build.hpp"

namespace visvol::app {
namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

class Thumbnails : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string(::testing::TempDir() + "/thumbs_" + std::to_string(getpid()) + ".vvp");
    storage::PackBuildParams p;
    p.field.nz = 24;
    p.field.ceiling_m = 200;
    p.field.range_posts = 8;
    p.lod_levels = 1;
    p.tff.band_offset_m = 60;
    p.tff.band_levels = 8;
    ASSERT_TRUE(storage::build_pack(fields::testing::fractal(65, 3), p, "", *path_).ok());
    auto pack = storage::Pack::open(*path_);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    pack_ = new std::shared_ptr<const storage::Pack>(*pack);
  }
  static void TearDownTestSuite() {
    delete pack_;
    std::remove(path_->c_str());
    delete path_;
  }
  // A straight path across the pack, 100 m above its lowest level.
  static msg::PathSample path(bool converged, std::uint64_t sequence) {
    const fields::VolumeGeometry g = (*pack_)->geometry(0);
    msg::PathSample s{};
    s.sequence = sequence;
    s.converged = converged;
    s.vertex_count = 17;
    for (std::uint32_t i = 0; i < s.vertex_count; ++i) {
      const double t = i / 16.0;
      s.vertices[i].position = {g.origin_x + t * (g.nx - 1) * g.spacing_m, g.origin_y - 0.5 * (g.ny - 1) * g.spacing_m,
                                g.top_m() - 20};
      s.vertices[i].visibility = 0.5;
    }
    return s;
  }
  static Result<std::unique_ptr<ThumbnailThread>> start(double max_hz, LatestValue<msg::ThumbnailSample>* sink) {
    ThumbnailConfig c;
    c.view = render::View::top;
    c.width_px = 96;
    c.height_px = 64;
    c.max_hz = max_hz;
    return ThumbnailThread::start(*pack_, c, sink);
  }
  static bool wait_for(const std::function<bool()>& done, double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return done();
  }
  static std::string* path_;
  static std::shared_ptr<const storage::Pack>* pack_;
};
std::string* Thumbnails::path_ = nullptr;
std::shared_ptr<const storage::Pack>* Thumbnails::pack_ = nullptr;

TEST_F(Thumbnails, DrawsWhenTheRopeComesToRestAndPublishesAPng) {
  LatestValue<msg::ThumbnailSample> sink;
  auto t = start(50.0, &sink);
  ASSERT_TRUE(t.ok()) << t.status().message();
  (*t)->paths().write(path(false, 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ((*t)->stats().rendered, 0u) << "a moving rope is not drawn";
  (*t)->paths().write(path(true, 2));
  ASSERT_TRUE(wait_for([&] { return (*t)->stats().rendered == 1; }, 10.0));
  const msg::ThumbnailSample* png = sink.take();
  ASSERT_NE(png, nullptr);
  ASSERT_GT(png->png_size_bytes, sizeof kPngSignature);
  EXPECT_EQ(std::memcmp(png->png, kPngSignature, sizeof kPngSignature), 0);
  // still at rest: no second picture of the same rest
  (*t)->paths().write(path(true, 3));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ((*t)->stats().rendered, 1u);
  EXPECT_EQ((*t)->stats().failed, 0u);
}

TEST_F(Thumbnails, RateLimitedAndOneLastPictureAtStop) {
  auto t = start(0.2, nullptr);  // one every 5 s at most
  ASSERT_TRUE(t.ok()) << t.status().message();
  (*t)->paths().write(path(true, 1));
  ASSERT_TRUE(wait_for([&] { return (*t)->stats().rendered == 1; }, 10.0));
  (*t)->paths().write(path(false, 2));  // moved, then at rest again within the 5 s
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  (*t)->paths().write(path(true, 3));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ((*t)->stats().rendered, 1u) << "the rate limit holds the second rest back";
  EXPECT_FALSE((*t)->write_last(::testing::TempDir() + "/never.png").ok()) << "only after stop";
  (*t)->stop();
  EXPECT_EQ((*t)->stats().rendered, 2u) << "stop draws where the rope ended";
  const std::string file = ::testing::TempDir() + "/thumb_" + std::to_string(getpid()) + ".png";
  ASSERT_TRUE((*t)->write_last(file).ok());
  std::FILE* f = std::fopen(file.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  unsigned char head[8] = {};
  const std::size_t got = std::fread(head, 1, sizeof head, f);
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::fclose(f);
  ASSERT_EQ(got, sizeof head);
  EXPECT_EQ(std::memcmp(head, kPngSignature, sizeof kPngSignature), 0);
  EXPECT_GT(size, 100);
  std::remove(file.c_str());
}

TEST_F(Thumbnails, NothingToShowIsSaidNotWritten) {
  auto t = start(1.0, nullptr);
  ASSERT_TRUE(t.ok());
  (*t)->stop();
  const Status s = (*t)->write_last(::testing::TempDir() + "/none.png");
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("none was rendered"), std::string::npos);
}

TEST_F(Thumbnails, BadRateIsRefused) {
  EXPECT_EQ(start(0.0, nullptr).status().code(), Errc::invalid_argument);
  EXPECT_EQ(start(1000.0, nullptr).status().code(), Errc::invalid_argument);
}

}  // namespace
}  // namespace visvol::app
