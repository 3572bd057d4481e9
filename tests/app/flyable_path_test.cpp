// The console's flyable-path thread: the rope's paths, fitted into the
// vehicle's envelope, reach the publisher and the renderer; judged here by
// the paths' own geometry, not by the fit's flag.
#include "app/flyable_path.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

#include "../fields/terrains.hpp"
#include "storage/pack_build.hpp"

namespace visvol::app {
namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

class Flyable : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    path_ = new std::string(::testing::TempDir() + "/flyable_" + std::to_string(getpid()) + ".vvp");
    storage::PackBuildParams p;
    p.field.nz = 24;
    p.field.ceiling_m = 300;
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
  static rt::VehicleEnvelope vehicle() {
    rt::VehicleEnvelope v;  // fixed-wing
    v.max_climb_deg = 5;
    v.max_descent_deg = 4;
    v.min_turn_radius_m = 0;
    return v;
  }
  static std::unique_ptr<PathFitter> fitter(int observers = 0) {
    auto f = PathFitter::create(*pack_, vehicle(), 64, observers);
    EXPECT_TRUE(f.ok()) << f.status().message();
    return f.ok() ? std::move(*f) : nullptr;
  }
  // A saw-tooth across the pack, 40 m then 150 m above its highest post (the
  // ends half way): climbs and descents far beyond the vehicle's.
  static void saw(rt::LimitedPath& l, std::uint64_t sequence, int vertices) {
    const fields::VolumeGeometry g = (*pack_)->geometry(0);
    const std::unique_ptr<PathFitter> f = fitter();
    const double highest = *std::max_element(f->terrain().height_m.begin(), f->terrain().height_m.end());
    msg::PathSample& s = l.path;
    s.sequence = sequence;
    std::snprintf(s.pack_id, sizeof s.pack_id, "flyable");
    s.vertex_count = static_cast<std::uint32_t>(vertices);
    for (int i = 0; i < vertices; ++i) {
      const double t = static_cast<double>(i) / (vertices - 1);
      const bool end = i == 0 || i == vertices - 1;
      s.vertices[i].position = {g.origin_x + (0.05 + 0.9 * t) * (g.nx - 1) * g.spacing_m,
                                g.origin_y - 0.5 * (g.ny - 1) * g.spacing_m,
                                highest + (end     ? 95.0
                                           : i % 2 ? 150.0
                                                   : 40.0)};
    }
    l.limits = rt::PathLimits{};
    l.limits.gains.clearance_m = 20;
  }
  static double steepest_deg(const msg::PathSample& s, bool climb) {
    double worst = 0;
    for (std::uint32_t k = 1; k < s.vertex_count; ++k) {
      const msg::WorldPoint& a = s.vertices[k - 1].position;
      const msg::WorldPoint& b = s.vertices[k].position;
      const double angle = std::atan2(b.z_m - a.z_m, std::hypot(b.x_m - a.x_m, b.y_m - a.y_m)) * kDeg;
      worst = std::max(worst, climb ? angle : -angle);
    }
    return worst;
  }
  static const msg::PathSample* wait_for(LatestValue<msg::PathSample>& sink) {
    for (int k = 0; k < 500; ++k) {
      if (const msg::PathSample* s = sink.take()) return s;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return nullptr;
  }

  static std::string* path_;
  static std::shared_ptr<const storage::Pack>* pack_;
};
std::string* Flyable::path_ = nullptr;
std::shared_ptr<const storage::Pack>* Flyable::pack_ = nullptr;

TEST_F(Flyable, ARopesPathReachesBothSinksInsideTheClimbAndDescentLimits) {
  LatestValue<msg::PathSample> publisher, renderer;
  auto f = FlyablePath::start(fitter(), &publisher, &renderer);
  ASSERT_TRUE(f.ok()) << f.status().message();
  saw((*f)->rope_paths().back(), 42, 9);
  msg::PathSample& rope = (*f)->rope_paths().back().path;
  rope.mode = msg::InteractionMode::spool;  // the interaction mode rides along
  rope.spool_paid_out_m = 1234.5;
  ASSERT_GT(steepest_deg(rope, true), 20.0);  // the rope's own path is far outside
  (*f)->rope_paths().publish();
  const msg::PathSample* sent = wait_for(publisher);
  ASSERT_NE(sent, nullptr);
  EXPECT_EQ(sent->sequence, 42u);
  EXPECT_STREQ(sent->pack_id, "flyable");
  EXPECT_EQ(sent->mode, msg::InteractionMode::spool);
  EXPECT_EQ(sent->spool_paid_out_m, 1234.5);
  EXPECT_GE(sent->vertex_count, 2u);
  EXPECT_LE(steepest_deg(*sent, true), 5.0 + 1e-9);
  EXPECT_LE(steepest_deg(*sent, false), 4.0 + 1e-9);
  EXPECT_GE(sent->min_clearance_m, 20.0 - 1e-6);
  EXPECT_GT(sent->length_m, 0.0);
  ASSERT_NE(wait_for(renderer), nullptr);
  (*f)->stop();
  EXPECT_EQ((*f)->stats().fitted, 1u);
  EXPECT_EQ((*f)->stats().failed, 0u);
}

TEST_F(Flyable, TheLastPathIsSentWhenStopping) {
  LatestValue<msg::PathSample> publisher;
  auto f = FlyablePath::start(fitter(), &publisher, nullptr, 0.5);  // a slow poll
  ASSERT_TRUE(f.ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the thread is asleep
  saw((*f)->rope_paths().back(), 7, 9);
  (*f)->rope_paths().publish();
  (*f)->stop();
  const msg::PathSample* sent = publisher.take();
  ASSERT_NE(sent, nullptr);
  EXPECT_EQ(sent->sequence, 7u);
}

TEST_F(Flyable, ALongRopeIsThinnedAndANonFiniteOneIsNotFitted) {
  const std::unique_ptr<PathFitter> f = fitter();
  const fields::VolumeGeometry g = (*pack_)->geometry(0);
  std::vector<rt::Vec3> rope;
  for (int i = 0; i <= 2000; ++i) {
    const double t = i / 2000.0;
    rope.emplace_back(g.origin_x + (0.05 + 0.9 * t) * (g.nx - 1) * g.spacing_m,
                      g.origin_y - 0.3 * (g.ny - 1) * g.spacing_m, g.z0_m + 200);
  }
  const rt::EnvelopeFit fit = f->fit(rope.data(), static_cast<int>(rope.size()), rt::ForceGains{});
  EXPECT_LE(fit.path.size(), msg::kMaxPathVertices);
  ASSERT_GE(fit.path.size(), 2u);
  EXPECT_EQ(fit.path.front(), rope.front());
  EXPECT_EQ(fit.path.back(), rope.back());
  rope[1000].z() = std::nan("");
  EXPECT_TRUE(f->fit(rope.data(), static_cast<int>(rope.size()), rt::ForceGains{}).path.empty());
}

TEST_F(Flyable, ObserversInForceAreBuiltOnceAndKeptUnderTheirHull) {
  std::unique_ptr<PathFitter> f = fitter(2);
  const fields::VolumeGeometry g = (*pack_)->geometry(0);
  rt::HullRequest r;
  r.sequence = 3;
  r.eye_height_m = 2;
  // standing on the terrain in the middle of the pack
  const double x = g.origin_x + 0.5 * (g.nx - 1) * g.spacing_m, y = g.origin_y - 0.5 * (g.ny - 1) * g.spacing_m;
  ASSERT_TRUE(r.add_hidden_from(rt::Vec3(x, y, f->terrain().at((g.nx - 1) / 2, (g.ny - 1) / 2))));
  f->set_observers(r);
  EXPECT_EQ(f->hull_failures(), 0);
  rt::LimitedPath l{};
  saw(l, 1, 9);
  std::vector<rt::Vec3> rope;
  for (std::uint32_t k = 0; k < l.path.vertex_count; ++k) {
    const msg::WorldPoint& w = l.path.vertices[k].position;
    rope.emplace_back(w.x_m, w.y_m, w.z_m);
  }
  const rt::EnvelopeFit with = f->fit(rope.data(), static_cast<int>(rope.size()), l.limits.gains);
  f->set_observers(rt::HullRequest{});  // none in force
  const rt::EnvelopeFit without = f->fit(rope.data(), static_cast<int>(rope.size()), l.limits.gains);
  // hiding from an observer on the ground asks for lower heights between the ends
  double sum_with = 0, sum_without = 0;
  for (std::size_t k = 1; k + 1 < with.path.size(); ++k) sum_with += with.path[k].z();
  for (std::size_t k = 1; k + 1 < without.path.size(); ++k) sum_without += without.path[k].z();
  EXPECT_LT(sum_with / static_cast<double>(std::max<std::size_t>(1, with.path.size() - 2)),
            sum_without / static_cast<double>(std::max<std::size_t>(1, without.path.size() - 2)));
}

// The pack cut short under a running session (an operator's cp over it):
// the fitter reads its bricks as checked copies, so it cannot fault; a path
// whose figures need a brick it cannot read any more is not sent, counted,
// and its F_p is NaN, never the zeros an unread brick reads as.
TEST_F(Flyable, APackCutShortUnderTheFitterIsCountedNotFatal) {
  // more bricks (11 x 11) than the fitter's cache holds (64): some are read again later
  const std::string copy = ::testing::TempDir() + "/flyable_cut_" + std::to_string(getpid()) + ".vvp";
  storage::PackBuildParams p;
  p.field.nz = 12;
  p.field.ceiling_m = 300;
  p.field.range_posts = 4;
  p.lod_levels = 1;
  ASSERT_TRUE(storage::build_pack(fields::testing::fractal(161, 3), p, "", copy).ok());
  auto pack = storage::Pack::open(copy, storage::PackAccess::inspect);
  ASSERT_TRUE(pack.ok()) << pack.status().message();
  auto made = PathFitter::create(*pack, vehicle(), 64, 0);
  ASSERT_TRUE(made.ok()) << made.status().message();
  std::filesystem::resize_file(copy, 4096);
  LatestValue<msg::PathSample> publisher;
  auto f = FlyablePath::start(std::move(*made), &publisher, nullptr);
  ASSERT_TRUE(f.ok()) << f.status().message();
  // a path along the pack's middle row, 100 m up
  const fields::VolumeGeometry g = (*pack)->geometry(0);
  const fields::Heightfield& ground = (*f)->fitter().terrain();
  rt::LimitedPath& l = (*f)->rope_paths().back();
  l = rt::LimitedPath{};
  l.path.sequence = 7;
  l.path.vertex_count = 9;
  for (int i = 0; i < 9; ++i) {
    const int col = 5 + i * (g.nx - 11) / 8, row = g.ny / 2;
    l.path.vertices[i].position = {g.origin_x + col * g.spacing_m, g.origin_y - row * g.spacing_m,
                                   ground.at(col, row) + 100.0};
  }
  l.limits.gains.clearance_m = 20;
  (*f)->rope_paths().publish();
  for (int k = 0; k < 500 && (*f)->stats().failed == 0; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  (*f)->stop();
  EXPECT_EQ((*f)->stats().failed, 1u);
  EXPECT_EQ((*f)->stats().fitted, 0u);
  EXPECT_EQ(publisher.take(), nullptr);
  PathFitter& fitter = (*f)->fitter();
  EXPECT_NE(fitter.read_error().find("ended at byte"), std::string::npos) << fitter.read_error();
  // described anyway (a session's final path): F_p unknown, the geometry kept
  const std::vector<rt::Vec3> path = {{g.origin_x + 100, g.origin_y - 100, ground.at(3, 3) + 100.0},
                                      {g.origin_x + (g.nx - 4) * g.spacing_m, g.origin_y - (g.ny - 4) * g.spacing_m,
                                       ground.at(g.nx - 4, g.ny - 4) + 100.0}};
  auto out_ptr = std::make_unique<msg::PathSample>();
  msg::PathSample& out = *out_ptr;
  EXPECT_FALSE(fitter.describe(path, out));
  EXPECT_TRUE(std::isnan(out.f_c));
  // and again over the same bricks (known unreadable now, not read again)
  out.f_c = 0;
  EXPECT_FALSE(fitter.describe(path, out));
  EXPECT_TRUE(std::isnan(out.f_c));
  EXPECT_EQ(out.vertex_count, 2u);
  EXPECT_GT(out.length_m, 0.0);
  std::remove(copy.c_str());
}

}  // namespace
}  // namespace visvol::app
