// visvol-hapticbench: the cost of the haptic path per 1 kHz tick (codec,
// driver, servo, the whole console tick) and the bus load of the protocol at
// 1 Mbit/s, nominal and with worst-case bit stuffing.
//
//   visvol-hapticbench                  bus load table, then Google Benchmark
//   visvol-hapticbench --load-only      only the table
//   (any --benchmark_* option of Google Benchmark)
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <optional>

#include "base/version.hpp"
#include "drivers/can/memory_bus.hpp"
#include "drivers/haptic/codec.hpp"
#include "drivers/haptic/device_driver.hpp"
#include "drivers/hapticsim/sim_device.hpp"
#include "rt/servo/servo.hpp"

namespace {

using namespace visvol;
constexpr std::int64_t kMs = 1'000'000;
constexpr double kBitRate = 1e6;

void print_bus_load() {
  std::printf("Bus load at 1 Mbit/s, classic CAN, 11-bit identifiers\n");
  std::printf("(frame bits = 47 + 8 x DLC; worst-case stuffing adds (34 + 8 x DLC - 1) / 4)\n\n");
  std::printf("%-13s %3s %8s %5s %8s %9s %10s\n", "frame", "dlc", "rate/s", "bits", "stuffed", "kbit/s", "stuffed");
  double nominal = 0.0, stuffed = 0.0;
  for (const haptic::FrameSpec& f : haptic::kFrames) {
    if (f.rate_hz <= 0.0) continue;
    const double n = f.rate_hz * haptic::frame_bits(f.dlc), s = f.rate_hz * haptic::frame_bits_stuffed(f.dlc);
    nominal += n;
    stuffed += s;
    std::printf("%-13s %3u %8.0f %5u %8u %9.1f %10.1f\n", f.name, f.dlc, f.rate_hz, haptic::frame_bits(f.dlc),
                haptic::frame_bits_stuffed(f.dlc), n / 1e3, s / 1e3);
  }
  std::printf("%-13s %3s %8s %5s %8s %9.1f %10.1f\n", "total", "", "", "", "", nominal / 1e3, stuffed / 1e3);
  std::printf(
      "\nload: %.1f %% nominal, %.1f %% with worst-case stuffing "
      "(emergency and NMT are rare events, not counted)\n\n",
      100.0 * nominal / kBitRate, 100.0 * stuffed / kBitRate);
}

void BM_DecodePosition(benchmark::State& state) {
  const can::CanFrame f = haptic::encode(haptic::PositionMsg{{12.34, -56.78, 90.12}, 1, 7}, 1);
  haptic::Message m;
  for (auto _ : state) {
    benchmark::DoNotOptimize(haptic::decode(f, m));
    benchmark::DoNotOptimize(m);
  }
}
BENCHMARK(BM_DecodePosition);

void BM_EncodeCommand(benchmark::State& state) {
  haptic::CommandMsg c{{0.123, -1.2, 0.9}, true, 0};
  for (auto _ : state) {
    ++c.sequence;
    benchmark::DoNotOptimize(haptic::encode(c, 1));
  }
}
BENCHMARK(BM_EncodeCommand);

// The device side of a bus for the driver benchmarks: a position every tick,
// a status every 10.
struct FakeDevice {
  can::MemoryBus bus{2, 256};
  std::uint8_t seq = 0;
  std::int64_t now_ns = 1'000 * kMs;

  FakeDevice() {
    bus.endpoint(0).set_filters(haptic::DeviceDriver::receive_filters(1), true);
    bus.set_time_ns(now_ns);
    (void)bus.endpoint(1).send(haptic::encode(haptic::HeartbeatMsg{haptic::NmtState::operational}, 1));
  }
  void tick() {
    now_ns += kMs;
    bus.set_time_ns(now_ns);
    (void)bus.endpoint(1).send(haptic::encode(haptic::PositionMsg{{1.0, 2.0, 3.0}, 1, seq}, 1));
    if (seq % 10 == 0) {
      haptic::StatusMsg s;
      s.nmt_state = haptic::NmtState::operational;
      (void)bus.endpoint(1).send(haptic::encode(s, 1));
    }
    ++seq;
    can::CanFrame sink[16];
    while (bus.endpoint(1).receive(sink, 16) > 0) {
    }
  }
};

void BM_DriverPollAndCommand(benchmark::State& state) {
  FakeDevice dev;
  auto driver = haptic::DeviceDriver::create(haptic::DriverConfig{}, dev.bus.endpoint(0));
  for (auto _ : state) {
    dev.tick();
    driver->poll(dev.now_ns);
    benchmark::DoNotOptimize(driver->command({0.1, 0.2, 0.3}, true));
  }
  if (!driver->operational()) state.SkipWithError("the driver never became operational");
}
BENCHMARK(BM_DriverPollAndCommand);

servo::ServoInput servo_input(double t, double x_mm) {
  servo::ServoInput in;
  in.time_s = t;
  in.device_pos_mm = Eigen::Vector3d(x_mm, 0.0, 0.0);
  in.grasp_button = true;
  in.sample_fresh = in.sample_valid = in.device_operational = in.point_valid = true;
  in.grad_fp_per_m = Eigen::Vector3d(0.01, 0.02, 0.3);
  return in;
}

void BM_ServoStep(benchmark::State& state) {
  servo::ServoConfig c;
  c.cue_gain_n_m = -0.5;
  auto s = servo::Servo::create(c);
  double t = 0.0;
  servo::ServoInput released = servo_input(t, 0.0);
  released.grasp_button = false;
  (void)s->step(released);
  for (auto _ : state) {
    t += 1e-3;
    benchmark::DoNotOptimize(s->step(servo_input(t, 10.0 + 5.0 * std::sin(t))));
  }
  if (s->counters().grasps != 1) state.SkipWithError("the servo never grasped");
}
BENCHMARK(BM_ServoStep);

// poll + servo + command: what the 1 kHz thread spends on the haptic device.
void BM_ConsoleTick(benchmark::State& state) {
  FakeDevice dev;
  auto driver = haptic::DeviceDriver::create(haptic::DriverConfig{}, dev.bus.endpoint(0));
  auto s = servo::Servo::create(servo::ServoConfig{});
  for (auto _ : state) {
    dev.tick();
    driver->poll(dev.now_ns);
    const haptic::DeviceSample& sample = driver->sample();
    servo::ServoInput in = servo_input(static_cast<double>(dev.now_ns) * 1e-9, sample.pos_mm[0]);
    in.sample_fresh = sample.fresh;
    in.sample_valid = sample.valid;
    in.device_operational = driver->operational();
    const servo::ServoOutput out = s->step(in);
    benchmark::DoNotOptimize(
        driver->command({out.device_force_n.x(), out.device_force_n.y(), out.device_force_n.z()}, out.device_enable));
  }
}
BENCHMARK(BM_ConsoleTick);

// The simulator's device per step (physics with 4 substeps, frames out).
void BM_SimDeviceStep(benchmark::State& state) {
  can::MemoryBus bus(2, 256);
  auto d = hapticsim::SimDevice::create(hapticsim::SimConfig{}, bus.endpoint(1), 0);
  std::int64_t now = 0;
  (void)bus.endpoint(0).send(haptic::encode(haptic::NmtMsg{haptic::NmtCommand::start, 1}));
  can::CanFrame sink[16];
  for (auto _ : state) {
    now += kMs;
    d->step(now);
    while (bus.endpoint(0).receive(sink, 16) > 0) {
    }
  }
}
BENCHMARK(BM_SimDeviceStep);

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-hapticbench")) return 0;
  print_bus_load();
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--load-only") == 0) return 0;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
