// visvol-dds-bench: what the DDS layer costs and how late its samples arrive.
//
// 1. Latency from the real-time hand-off (LatestValue::publish) to a
//    subscriber in another process on loopback, p50/p99/max, for two
//    producers: events spaced wider than the path rate (each is published as
//    soon as the publisher thread sees it), and a 1 kHz producer with the
//    50 Hz path rate (the executive's pattern: the age of what arrives).
//    Also the publisher thread's CPU time at that load, and for reference
//    DDS alone (dds_write called by the producer to the subscriber).
// 2. Google Benchmark micro-benchmarks: the producer's hand-off, conversion,
//    dds_write of a path with and without a subscriber, command validation.
//
// The executive's timing with and without publishing is measured once the
// executive exists (rt/exec); this tool cannot yet.
//
//   visvol-dds-bench [--domain N] [--samples N] [--no-latency] [benchmark flags]
#include <benchmark/benchmark.h>
#include <dirent.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "base/version.hpp"
#include "drivers/dds/command_processor.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/path_publisher.hpp"

extern char** environ;

namespace {

using namespace visvol;
using namespace visvol::dds;
using namespace visvol::msg;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kEndOfRun = ~std::uint64_t{0};
std::uint32_t g_domain = 219;  // tests/drivers/dds/test_domains.hpp

ParticipantConfig config(const std::string& ns) {
  ParticipantConfig c;
  c.domain_id = g_domain;
  c.cyclone_xml = std::string(loopback_config());
  c.topic_namespace = ns;
  return c;
}

std::unique_ptr<Participant> participant_or_die(const std::string& ns) {
  Result<std::unique_ptr<Participant>> p = Participant::create(config(ns));
  if (!p.ok()) {
    std::fprintf(stderr, "visvol-dds-bench: %s\n", p.status().message().c_str());
    std::exit(1);
  }
  return std::move(*p);
}

void fill(PathSample& s, std::uint64_t seq, std::uint32_t vertices) {
  s.sequence = seq;
  copy_text(s.pack_id, "bench");
  s.objective = Objective::hide;
  s.vertex_count = vertices;
  for (std::uint32_t i = 0; i < vertices; ++i) {
    s.vertices[i] = {{544000.0 + i, 4189000.0, 100.0}, 0.5, 20.0};
  }
  s.stamp_ns = now_stamp_ns();  // last: the hand-off time
}

struct Percentiles {
  double p50_us = 0, p99_us = 0, max_us = 0;
  std::size_t count = 0;
};

Percentiles summarize(std::vector<double> v) {
  Percentiles p;
  p.count = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
  };
  p.p50_us = at(0.50);
  p.p99_us = at(0.99);
  p.max_us = v.back();
  return p;
}

// The subscriber process: receive until the end marker, then report the
// latencies (receive time minus the stamp set at hand-off) on `out`.
[[noreturn]] void subscriber(const std::string& ns, int ready_fd, int out_fd) {
  std::unique_ptr<Participant> p = participant_or_die(ns);
  QosPtr qos = reader_qos(Topic::path_update);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  Result<Reader> reader = Reader::create(*p, Topic::path_update, qos.get());
  if (!reader.ok()) std::_Exit(1);
  (void)!::write(ready_fd, "r", 1);
  std::vector<double> latencies;
  bool done = false;
  while (!done) {
    (void)reader->wait(1.0);
    (void)reader->take<visvol_msgs_msg_dds__PathUpdate_>(
        [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
          const std::int64_t now = now_stamp_ns();
          if (m.sequence_number == kEndOfRun) {
            done = true;
            return;
          }
          latencies.push_back(static_cast<double>(now - from_ros_time(m.header.stamp)) * 1e-3);
        },
        64);
  }
  const Percentiles s = summarize(latencies);
  (void)!::write(out_fd, &s, sizeof s);
  std::_Exit(0);
}

// CPU time of the publisher thread so far, from its scheduler statistics.
double publisher_cpu_s() {
  DIR* dir = ::opendir("/proc/self/task");
  if (!dir) return -1.0;
  double cpu_s = -1.0;
  while (dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    const std::string base = std::string("/proc/self/task/") + e->d_name;
    std::ifstream comm(base + "/comm");
    std::string name;
    std::getline(comm, name);
    if (name != "visvol-dds-pub") continue;
    std::ifstream stat(base + "/schedstat");
    double ns = 0.0;
    if (stat >> ns) cpu_s = ns * 1e-9;
  }
  ::closedir(dir);
  return cpu_s;
}

struct LatencyRun {
  const char* label;
  double producer_hz;
  double path_hz;
  bool direct;  // the producer calls PathPublisher::publish itself: DDS alone
};

void latency(const LatencyRun& run, std::size_t samples) {
  const std::string ns = "bench" + std::to_string(::getpid());
  int ready[2], out[2];
  if (::pipe(ready) != 0 || ::pipe(out) != 0) return;
  // a fresh process (this binary again), not a fork of one with DDS threads
  const std::string domain = std::to_string(g_domain), rfd = std::to_string(ready[1]), ofd = std::to_string(out[1]);
  const char* args[] = {"/proc/self/exe", "--subscriber", ns.c_str(), domain.c_str(),
                        rfd.c_str(),      ofd.c_str(),    nullptr};
  pid_t child = -1;
  if (posix_spawn(&child, "/proc/self/exe", nullptr, nullptr, const_cast<char**>(args), environ) != 0) {
    std::printf("%-44s  cannot start the subscriber process\n", run.label);
    return;
  }
  char byte;
  if (::read(ready[0], &byte, 1) != 1) return;

  std::unique_ptr<Participant> p = participant_or_die(ns);
  PublisherConfig pc;
  pc.path_hz = run.path_hz;
  Result<std::unique_ptr<LivePublisher>> live = LivePublisher::start(*p, pc);
  Result<std::unique_ptr<PathPublisher>> direct = PathPublisher::create(*p);
  if (!live.ok() || !direct.ok()) return;
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (((*live)->path_subscribers() < 1 || (*direct)->path_update_subscribers() < 1) && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }

  const double cpu0 = publisher_cpu_s();
  const auto t0 = Clock::now();
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / run.producer_hz));
  // a producer faster than the path rate runs long enough for `samples`
  // publications at path_hz
  const std::size_t handoffs =
      run.producer_hz > run.path_hz
          ? static_cast<std::size_t>(static_cast<double>(samples) * run.producer_hz / run.path_hz)
          : samples;
  auto sample = std::make_unique<PathSample>();
  auto next = t0;
  for (std::size_t i = 1; i <= handoffs; ++i) {
    next += period;
    std::this_thread::sleep_until(next);
    if (run.direct) {
      fill(*sample, i, 64);
      (void)(*direct)->publish(*sample);
    } else {
      fill((*live)->path().back(), i, 64);
      (*live)->path().publish();
    }
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu_s = publisher_cpu_s() - cpu0;
  const std::uint64_t published = (*live)->stats().paths;
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  fill(*sample, kEndOfRun, 0);
  (void)(*direct)->publish(*sample);
  (void)(*direct)->wait_for_delivery(2.0);
  (void)(*live)->stop();

  Percentiles s;
  const bool got = ::read(out[0], &s, sizeof s) == static_cast<ssize_t>(sizeof s);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (!got) {
    std::printf("%-44s  no result from the subscriber\n", run.label);
    return;
  }
  std::printf("%-44s  p50 %7.1f us  p99 %7.1f us  max %8.1f us  (%zu samples, p99 %s 1 ms)\n", run.label, s.p50_us,
              s.p99_us, s.max_us, s.count, s.p99_us < 1000.0 ? "<" : ">=");
  if (!run.direct) {
    std::printf("%-44s  publisher thread %.2f%% of a core (%llu paths in %.1f s)\n", "",
                cpu_s >= 0.0 ? 100.0 * cpu_s / wall_s : -1.0, static_cast<unsigned long long>(published), wall_s);
  }
  for (int fd : {ready[0], ready[1], out[0], out[1]}) ::close(fd);
}

// Micro-benchmarks ----------------------------------------------------------------

// The real-time side: fill the back slot in place and publish it.
void BM_HandOffPath(benchmark::State& state) {
  auto handoff = std::make_unique<LatestValue<PathSample>>();
  const auto vertices = static_cast<std::uint32_t>(state.range(0));
  std::uint64_t seq = 0;
  for (auto _ : state) {
    fill(handoff->back(), ++seq, vertices);
    handoff->publish();
    benchmark::DoNotOptimize(handoff.get());
  }
}
BENCHMARK(BM_HandOffPath)->Arg(64)->Arg(512);

void BM_ConvertPath(benchmark::State& state) {
  auto messages = std::make_unique<PathMessages>(kDefaultFrameId);
  auto sample = std::make_unique<PathSample>();
  fill(*sample, 1, static_cast<std::uint32_t>(state.range(0)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(messages->fill(*sample).ok());
  }
}
BENCHMARK(BM_ConvertPath)->Arg(64)->Arg(512);

// Convert and dds_write (nav_msgs/Path and PathUpdate), with 0 or 1
// subscriber (in this process: Cyclone delivers locally).
void BM_PublishPath(benchmark::State& state) {
  static std::unique_ptr<Participant> p = participant_or_die("micro" + std::to_string(::getpid()));
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  std::unique_ptr<Reader> reader;
  if (state.range(1) > 0) {
    Result<Reader> r = Reader::create(*p, Topic::path_update);
    if (r.ok()) reader = std::make_unique<Reader>(std::move(*r));
    (void)(*pub)->wait_for_subscribers(1, 5.0);
  }
  auto sample = std::make_unique<PathSample>();
  std::uint64_t seq = 0;
  for (auto _ : state) {
    fill(*sample, ++seq, static_cast<std::uint32_t>(state.range(0)));
    if (!(*pub)->publish(*sample).ok()) state.SkipWithError("publish failed");
  }
}
BENCHMARK(BM_PublishPath)
    ->ArgNames({"vertices", "subscribers"})
    ->Args({64, 0})
    ->Args({64, 1})
    ->Args({512, 0})
    ->Args({512, 1});

void BM_ValidateCommand(benchmark::State& state) {
  CommandLimits limits;
  limits.min = {0.0, 0.0, 0.0};
  limits.max = {1000.0, 1000.0, 1000.0};
  Command c{};
  c.kind = CommandKind::set_constraints;
  copy_text(c.source, "bench");
  c.constraints.count = 8;
  for (std::uint32_t i = 0; i < 8; ++i) {
    c.constraints.items[i] = {ConstraintKind::hidden_from, {100.0 + i, 200.0, 50.0}, 0.0};
  }
  CommandMessage msg;
  const visvol_msgs_msg_dds__Command_& m = msg.fill(c);
  Command out{};
  for (auto _ : state) benchmark::DoNotOptimize(decode_and_validate(m, limits, out).ok());
}
BENCHMARK(BM_ValidateCommand);

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-dds-bench")) return 0;
  // the subscriber side of the latency runs: --subscriber NS DOMAIN READY_FD OUT_FD
  if (argc == 6 && std::string(argv[1]) == "--subscriber") {
    g_domain = static_cast<std::uint32_t>(std::strtoul(argv[3], nullptr, 10));
    subscriber(argv[2], std::atoi(argv[4]), std::atoi(argv[5]));
  }
  bool run_latency = true;
  std::size_t samples = 500;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--no-latency") {
      run_latency = false;
    } else if ((a == "--domain" || a == "--samples") && i + 1 < argc) {
      char* end = nullptr;
      const unsigned long v = std::strtoul(argv[++i], &end, 10);
      if (*end != '\0' || (a == "--domain" && v > kMaxDomainId) || (a == "--samples" && v == 0)) {
        std::fprintf(stderr, "visvol-dds-bench: %s %s: out of range\n", a.c_str(), argv[i]);
        return 2;
      }
      if (a == "--domain") {
        g_domain = static_cast<std::uint32_t>(v);
      } else {
        samples = v;
      }
    } else {
      rest.push_back(argv[i]);
    }
  }
  if (run_latency) {
    std::printf(
        "Latency, real-time hand-off to a subscriber in another process "
        "(loopback, domain %u, 64-vertex paths):\n",
        g_domain);
    latency({"DDS alone: dds_write to the subscriber", 40.0, 50.0, true}, samples);
    latency({"events every 25 ms (each published at once)", 40.0, 50.0, false}, samples);
    latency({"1 kHz producer, 50 Hz path rate", 1000.0, 50.0, false}, samples);
    std::printf(
        "Executive timing with and without publishing: visvol-rtbench --compare-dds N "
        "(alternating runs of the 1 kHz loop, medians side by side).\n\n");
  }
  int bench_argc = static_cast<int>(rest.size());
  benchmark::Initialize(&bench_argc, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
