// What the executive's tests share (executive_test, executive_commands_test,
// executive_device_test): a pack built once per test binary, the executive
// ticked in simulated time, the simulated haptic device on its bus and a
// device whose answers a test chooses.
#pragma once

#include "rt/exec/executive.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

#include "../../fields/terrains.hpp"
#include "drivers/haptic/can_device.hpp"
#include "drivers/hapticsim/simulated_device.hpp"
#include "rt/exec/periodic_loop.hpp"
#include "rt/rope/point_hull_maker.hpp"
#include "storage/pack_build.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::rt::executive_test {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::uint64_t kMiB = 1024 * 1024;

inline std::string pack_path(const std::string& stem) { return stem + "_" + std::to_string(::getpid()) + ".vvp"; }

// A pack of posts x posts fractal terrain (30 m posts, 32 levels, three
// levels of detail) at a cube range of range_posts.
inline std::string build(const std::string& stem, int posts, std::uint32_t seed, int range_posts = 8) {
  const fields::Heightfield hf = fields::testing::fractal(posts, seed);
  storage::PackBuildParams p;
  p.field.nz = 32;
  p.field.ceiling_m = 200;
  p.field.range_posts = range_posts;
  p.lod_levels = 3;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  const std::string path = pack_path(stem);
  EXPECT_TRUE(storage::build_pack(hf, p, "", path).ok());
  return path;
}

// World point at fractions of the finest level, `up_m` above the terrain there.
inline Vec3 point_at(const storage::ResidentPack& r, double fx, double fy, double up_m) {
  const fields::VolumeGeometry g = r.level(0).geometry();
  const double x = g.origin_x + fx * (g.nx - 1) * g.spacing_m, y = g.origin_y - fy * (g.ny - 1) * g.spacing_m;
  return {x, y, fields::FieldSampler<storage::ResidentLevel>(r.level(0)).height(x, y) + up_m};
}

class ExecutiveTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { path_ = new std::string(build("executive", 129, 7)); }
  static void TearDownTestSuite() {
    std::remove(path_->c_str());
    delete path_;
  }
  void SetUp() override {
    auto pack = storage::Pack::open(*path_);
    ASSERT_TRUE(pack.ok());
    storage::ResidentConfig rc;
    rc.budget_bytes = 64 * kMiB;  // the whole pack
    auto r = storage::ResidentPack::create(*pack, rc);
    ASSERT_TRUE(r.ok()) << r.status().message();
    field_ = std::move(*r);
    config_.start_m = point_at(*field_, 0.15, 0.2, 150);
    config_.end_m = point_at(*field_, 0.85, 0.75, 150);
    config_.segments = 32;
    config_.max_segments = 64;
    config_.gains.clearance_m = 30;
    std::strcpy(config_.pack_id, "fractal");
  }

  std::unique_ptr<Executive> make(HapticDevice* device = nullptr, DeviceSimulation* sim = nullptr) {
    ExecutiveOutputs out;
    out.path = &paths_;
    out.limited_path = &limited_;
    out.device = &device_;
    out.acks = &acks_;
    auto e = Executive::create(config_, *field_, device, sim, &commands_, out);
    EXPECT_TRUE(e.ok()) << e.status().message();
    if (e.ok()) (*e)->warm_up();
    return e.ok() ? std::move(*e) : nullptr;
  }

  // Runs `ticks` ticks of 1 ms in simulated time.
  void run(Executive& e, int ticks) {
    for (int k = 0; k < ticks; ++k) {
      now_ns_ += kMs;
      e.tick({tick_++, now_ns_, now_ns_, kMs});
    }
  }

  msg::Command command(msg::CommandKind kind, std::uint64_t sequence) {
    msg::Command c{};
    c.kind = kind;
    c.sequence = sequence;
    msg::copy_text(c.source, "test");
    return c;
  }
  msg::CommandAck next_ack() {
    msg::CommandAck a{};
    EXPECT_TRUE(acks_.try_pop(a));
    return a;
  }
  // The reason of the next ack, which must say the command failed.
  std::string next_failure() {
    const msg::CommandAck a = next_ack();
    EXPECT_EQ(a.result, msg::AckResult::failed) << a.sequence << ": " << a.reason;
    return a.reason;
  }

  // A hull builder for `observers` beside e's loop, started.
  std::unique_ptr<ConstraintHulls> make_hulls(Executive& e, int observers) {
    auto h = ConstraintHulls::create(field_->level(0), observers);
    EXPECT_TRUE(h.ok()) << h.status().message();
    if (!h.ok()) return nullptr;
    const Status s = e.set_constraint_hulls(h->get());
    EXPECT_TRUE(s.ok()) << s.message();
    (*h)->start();
    return std::move(*h);
  }

  // Ticks until `n` hull sets are in force (the builder works beside).
  void wait_for_sets(Executive& e, std::uint64_t n) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (e.counters().hull_sets < n && std::chrono::steady_clock::now() < end) {
      run(e, 1);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  static void add(msg::Command& c, msg::ConstraintKind kind, const Vec3& p, double height_m = 0) {
    c.constraints.items[c.constraints.count++] = {kind, {p.x(), p.y(), p.z()}, height_m};
  }

  // The highest height above the finest terrain along the rope.
  double highest_agl(const Executive& e) const {
    const fields::FieldSampler<storage::ResidentLevel> ground(field_->level(0));
    double highest = -INFINITY;
    for (int i = 0; i <= e.rope().segments(); ++i) {
      const Vec3& v = e.rope().vertices()[i];
      highest = std::max(highest, v.z() - ground.height(v.x(), v.y()));
    }
    return highest;
  }

  inline static std::string* path_ = nullptr;
  std::unique_ptr<storage::ResidentPack> field_;
  ExecutiveConfig config_;
  msg::CommandQueue commands_;
  msg::AckQueue acks_;
  LatestValue<msg::PathSample> paths_;
  LatestValue<LimitedPath> limited_;  // the flyable-path fitter's hand-off
  LatestValue<msg::DeviceStatusSample> device_;
  std::int64_t now_ns_ = 10'000 * kMs;
  std::uint64_t tick_ = 0;
};

// The hand grabs the rope in the middle of the workspace and pulls east.
inline const char* const kPullScript =
    "0.5 move 0 0 0 0.2\n"
    "1.0 pull 60 0 0 1.0\n"
    "4.0 release\n";

// The simulated device on its in-process bus, and the console's CAN driver
// talking to it (as the console wires them).
struct SimRig {
  std::unique_ptr<hapticsim::SimulatedDevice> sim;
  std::optional<haptic::CanDevice> device;
};

inline std::unique_ptr<SimRig> simulated(const char* script, std::int64_t start_ns) {
  hapticsim::SimConfig sc;
  auto s = hapticsim::parse_script(script, "test script", sc.workspace_half_mm);
  EXPECT_TRUE(s.ok()) << s.status().message();
  if (!s.ok()) return nullptr;
  auto rig = std::make_unique<SimRig>();
  auto sim = hapticsim::SimulatedDevice::create(sc, *s, start_ns);
  EXPECT_TRUE(sim.ok()) << sim.status().message();
  if (!sim.ok()) return nullptr;
  rig->sim = std::move(*sim);
  auto device = haptic::CanDevice::create(haptic::DriverConfig{}, rig->sim->console_bus());
  EXPECT_TRUE(device.ok()) << device.status().message();
  if (!device.ok()) return nullptr;
  rig->device.emplace(std::move(*device));
  return rig;
}

// A device whose every answer the test chooses: what the executive makes of
// the device's state, health and command results, apart from any bus.
class FakeDevice final : public HapticDevice {
 public:
  void poll(std::int64_t now_ns) override {
    last_poll_ns = now_ns;
    ++polls;
  }
  const HapticSample& sample() const override { return sample_; }
  HapticState state() const override { return health_.state; }
  HapticHealth health() const override { return health_; }
  Errc command(const Eigen::Vector3d& force_n, bool enable) override {
    last_force_n = force_n;
    last_enable = enable;
    return answer;
  }

  HapticSample sample_;
  HapticHealth health_;
  Errc answer = Errc::ok;
  std::int64_t last_poll_ns = 0;
  int polls = 0;
  Eigen::Vector3d last_force_n = Eigen::Vector3d::Constant(NAN);
  bool last_enable = true;
};

// The distance from p to the nearest point of the rope.
inline double distance_to(const Rope& r, const Vec3& p) {
  double best = INFINITY;
  for (int i = 0; i < r.segments(); ++i) {
    const Vec3 a = r.vertices()[i], d = r.vertices()[i + 1] - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * d - p).norm());
  }
  return best;
}

}  // namespace visvol::rt::executive_test
