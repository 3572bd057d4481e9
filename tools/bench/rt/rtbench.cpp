// visvol-rtbench: the console's 1 kHz loop measured as it runs: the rope,
// the servo and the simulated device over the in-process bus, the rope
// dragged across a pack eight times larger than its tile budget, with
// cyclictest (Debian rt-tests) run beside it at the same period and priority.
//
//   visvol-rtbench [--seconds N] [--json] [--pack PACK] [--dds]
//
// Prints wake-up latency p50/p99/p99.9/max and compute time p50/p99 of the
// loop and of cyclictest, heap allocations and page faults in the loop thread,
// and resident memory against the budget. --json ends with one object.
// With --dds the executive's path and device hand-offs are published by the
// DDS publisher thread (loopback); --compare-dds N alternates N runs without
// and N with it and prints the medians side by side.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "base/cli_numbers.hpp"
#include "base/version.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/haptic/can_device.hpp"
#include "drivers/hapticsim/simulated_device.hpp"
#include "fields/gdal/dem_import.hpp"
#include "rt/exec/executive.hpp"
#include "rt/exec/memory_budget.hpp"
#include "rt/exec/periodic_loop.hpp"
#include "rt/exec/realtime.hpp"
#include "storage/pack_build.hpp"
#include "storage/resident_pack.hpp"
#include "tests/support/alloc_counter.hpp"

extern char** environ;

namespace {

using namespace visvol;
constexpr std::uint64_t kMiB = 1024 * 1024;

struct Options {
  double seconds = 10;
  bool json = false;
  std::string pack;
  bool dds = false;
  int priority = 80;
  int cpu = -1;
  int segments = 128;
  double tile_ratio = 8;  // pack bytes per tile-budget byte
  double budget_mib = 256;
  std::uint32_t domain = 222;
  int compare_rounds = 0;  // --compare-dds: pairs of runs without and with publishing
};

// One run's figures, for the side-by-side comparison.
struct Figures {
  double wake_p50_us = 0, wake_p99_us = 0, compute_p50_us = 0, compute_p99_us = 0, compute_p999_us = 0;
  double cyclictest_p99_us = 0;
  std::uint64_t overruns = 0;
};

// The loop thread's allocations, counted after warm-up.
class CountingTask final : public rt::PeriodicTask {
 public:
  explicit CountingTask(rt::Executive& e) : e_(e) {}
  void warm_up() override {
    e_.warm_up();
    (void)testing::thread_allocation_count();
  }
  void tick(const rt::TickTime& t) override {
    if (t.index == 1000) start_ = testing::thread_allocation_count();
    e_.tick(t);
    if (t.index >= 1000) allocations_.store(testing::thread_allocation_count() - start_);
  }
  void safe_state() override { e_.safe_state(); }
  std::uint64_t allocations() const { return allocations_.load(); }

 private:
  rt::Executive& e_;
  std::uint64_t start_ = 0;
  std::atomic<std::uint64_t> allocations_{0};
};

// The default pack: the bundled San Francisco North DEM, built once into the
// build tree.
Result<std::string> default_pack() {
  const std::string demo = std::string(VISVOL_SOURCE_DIR) + "/out/sf_north.vvp";
  if (access(demo.c_str(), R_OK) == 0) return demo;
  const std::string cached = "rtbench_sf_north.vvp";
  if (access(cached.c_str(), R_OK) == 0) return cached;
  std::fprintf(stderr, "visvol-rtbench: building %s from the bundled DEM (once)...\n", cached.c_str());
  fields::ImportOptions io;
  io.nodata = fields::NodataPolicy::fill;
  auto hf = fields::import_dem(std::string(VISVOL_SOURCE_DIR) + "/tests/data/sf_north_utm10_30m.tif", io);
  if (!hf.ok()) return hf.status();
  storage::PackBuildParams p;
  VISVOL_RETURN_IF_ERROR(storage::build_pack(*hf, p, R"({"path":"tests/data/sf_north_utm10_30m.tif"})", cached));
  return cached;
}

struct Cyclictest {
  bool ran = false;
  std::string error;
  double p50_us = 0, p99_us = 0, p999_us = 0, max_us = 0, avg_us = 0;
  std::uint64_t cycles = 0;
};

pid_t start_cyclictest(const Options& o, const std::string& json_path) {
  std::vector<std::string> args = {"cyclictest",
                                   "-m",
                                   "-q",
                                   "-t1",
                                   "-i1000",
                                   "-h",
                                   "10000",
                                   "-p" + std::to_string(o.priority),
                                   "-D" + std::to_string(static_cast<int>(std::ceil(o.seconds))),
                                   "--json=" + json_path};
  if (o.cpu >= 0) args.push_back("-a" + std::to_string(o.cpu));
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, "cyclictest", &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

Cyclictest finish_cyclictest(pid_t pid, const std::string& json_path) {
  Cyclictest c;
  if (pid < 0) {
    c.error = "cyclictest could not be started (install rt-tests: tools/deps.sh rt)";
    return c;
  }
  int status = 0;
  waitpid(pid, &status, 0);
  std::ifstream in(json_path);
  if (!in) {
    c.error = "cyclictest wrote no results (exit status " + std::to_string(WEXITSTATUS(status)) + ")";
    return c;
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    const nlohmann::json& t = j.at("thread").at("0");
    c.cycles = t.at("cycles").get<std::uint64_t>();
    c.max_us = t.at("max").get<double>();
    c.avg_us = t.at("avg").get<double>();
    std::vector<std::pair<int, std::uint64_t>> bins;
    for (const auto& [k, v] : t.at("histogram").items()) bins.emplace_back(std::stoi(k), v.get<std::uint64_t>());
    std::sort(bins.begin(), bins.end());
    auto percentile = [&](double p) {
      const auto rank = static_cast<std::uint64_t>(std::ceil(p * static_cast<double>(c.cycles)));
      std::uint64_t seen = 0;
      for (const auto& [us, n] : bins) {
        seen += n;
        if (seen >= rank) return us + 1.0;  // upper edge of the 1 us bin, as the loop's histogram
      }
      return c.max_us;  // in the overflow beyond 10 ms
    };
    c.p50_us = percentile(0.5);
    c.p99_us = std::min(percentile(0.99), c.max_us);
    c.p999_us = std::min(percentile(0.999), c.max_us);
    c.ran = true;
  } catch (const std::exception& e) {
    c.error = std::string("cyclictest results unreadable: ") + e.what();
  }
  std::remove(json_path.c_str());
  return c;
}

int run(const Options& o, Figures& fig) {
  auto pack_path = o.pack.empty() ? default_pack() : Result<std::string>(o.pack);
  if (!pack_path.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", pack_path.status().message().c_str());
    return 1;
  }
  auto pack = storage::Pack::open(*pack_path);
  if (!pack.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", pack.status().message().c_str());
    return 2;
  }
  rt::RealtimeConfig rtc;
  rtc.priority = o.priority;
  rtc.cpu = o.cpu;
  rt::RealtimeReport realtime;
  rt::lock_process_memory(rtc, realtime);

  std::unique_ptr<dds::Participant> participant;
  std::unique_ptr<dds::LivePublisher> publisher;
  if (o.dds) {
    dds::ParticipantConfig pc;
    pc.domain_id = o.domain;
    pc.cyclone_xml = std::string(dds::loopback_config());
    auto p = dds::Participant::create(pc);
    if (!p.ok()) {
      std::fprintf(stderr, "visvol-rtbench: %s\n", p.status().message().c_str());
      return 1;
    }
    participant = std::move(*p);
    auto pub = dds::LivePublisher::start(*participant, dds::PublisherConfig());
    if (!pub.ok()) {
      std::fprintf(stderr, "visvol-rtbench: %s\n", pub.status().message().c_str());
      return 1;
    }
    publisher = std::move(*pub);
  }

  // the tiles get an eighth of the pack; the whole process is held to the budget
  rt::MemoryBudget budget(static_cast<std::uint64_t>(o.budget_mib * kMiB));
  budget.reserve("process", rt::resident_bytes());
  storage::ResidentConfig rc;
  rc.budget_bytes = static_cast<std::uint64_t>(static_cast<double>((*pack)->file_bytes()) / o.tile_ratio);
  rc.margin_m = 300;
  rc.poll_interval_s = 0.005;
  budget.reserve("tiles", rc.budget_bytes);
  if (Status s = budget.check(); !s.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", s.message().c_str());
    return 2;
  }
  auto field = storage::ResidentPack::create(*pack, rc);
  if (!field.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", field.status().message().c_str());
    return 2;
  }
  storage::ResidentPack& f = **field;
  const fields::VolumeGeometry g = f.level(0).geometry();
  const fields::FieldSampler<storage::ResidentLevel> ground(f.level(0));
  auto at = [&](double fx, double fy) {
    const double x = g.origin_x + fx * (g.nx - 1) * g.spacing_m, y = g.origin_y - fy * (g.ny - 1) * g.spacing_m;
    return rt::Vec3(x, y, ground.height(x, y) + 150);
  };

  // an operator who keeps grabbing and pulling the rope
  hapticsim::SimConfig sc;
  std::string script = "0.5 move 0 0 0 0.3\n";
  for (double t = 1.0; t < o.seconds; t += 3.0) {
    char line[160];
    std::snprintf(line, sizeof line, "%.1f pull %d %d %d 1.0\n%.1f release\n%.1f move 0 0 0 0.5\n", t,
                  static_cast<int>(30 * std::cos(t)), static_cast<int>(30 * std::sin(t)), -10, t + 1.5, t + 2.0);
    script += line;
  }
  auto parsed = hapticsim::parse_script(script, "rtbench script", sc.workspace_half_mm);
  auto sim = hapticsim::SimulatedDevice::create(sc, std::move(*parsed), rt::monotonic_ns());
  if (!sim.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", sim.status().message().c_str());
    return 1;
  }
  rt::ExecutiveConfig ec;
  ec.start_m = at(0.05, 0.1);
  ec.end_m = at(0.35, 0.3);
  ec.segments = o.segments;
  ec.max_segments = std::max(o.segments, 256);
  msg::CommandQueue commands;
  msg::AckQueue acks;
  rt::ExecutiveOutputs out;
  if (publisher) {
    out.path = &publisher->path();
    out.device = &publisher->device_status();
  }
  out.acks = &acks;
  auto device = haptic::CanDevice::create(haptic::DriverConfig{}, (*sim)->console_bus());
  if (!device.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", device.status().message().c_str());
    return 1;
  }
  auto e = rt::Executive::create(ec, f, &*device, sim->get(), &commands, out);
  if (!e.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", e.status().message().c_str());
    return 1;
  }

  const std::string ct_json = "rtbench_cyclictest_" + std::to_string(getpid()) + ".json";
  f.set_reader_active(true);
  f.start_pager();
  CountingTask task(**e);
  rt::PeriodicLoop loop(task);
  rt::LoopConfig lc;
  lc.realtime = rtc;
  lc.overrun_limit = 1000;  // measure, do not intervene
  lc.settle_ticks = 1000;
  const pid_t ct = start_cyclictest(o, ct_json);
  if (Status s = loop.start(lc); !s.ok()) {
    std::fprintf(stderr, "visvol-rtbench: %s\n", s.message().c_str());
    return 1;
  }
  // drag the rope's ends across the pack, two diagonals there and back
  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t rss_peak = 0;
  std::uint64_t seq = 0;
  for (;;) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (t >= o.seconds) break;
    const double phase = std::fmod(t / 10.0, 2.0), u = 0.05 + 0.55 * (phase < 1 ? phase : 2 - phase);
    msg::Command m{};
    m.kind = msg::CommandKind::set_endpoints;
    m.sequence = ++seq;
    const rt::Vec3 a = at(u, u + 0.05), b = at(u + 0.3, u + 0.25);
    m.endpoints.start = {a.x(), a.y(), a.z()};
    m.endpoints.end = {b.x(), b.y(), b.z()};
    (void)commands.try_push(m);
    msg::CommandAck ack;
    while (acks.try_pop(ack)) {
    }
    rss_peak = std::max(rss_peak, rt::resident_bytes());
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  const rt::LoopRun run = loop.stop();
  f.set_reader_active(false);
  f.stop_pager();
  const Cyclictest c = finish_cyclictest(ct, ct_json);
  rss_peak = std::max(rss_peak, rt::resident_bytes());
  if (publisher) (void)publisher->stop();
  const storage::ResidentStats ts = f.stats();

  const double wake_p99 = run.wake_latency.percentile_us(0.99);
  fig.wake_p50_us = run.wake_latency.percentile_us(0.5);
  fig.wake_p99_us = wake_p99;
  fig.compute_p50_us = run.compute.percentile_us(0.5);
  fig.compute_p99_us = run.compute.percentile_us(0.99);
  fig.compute_p999_us = run.compute.percentile_us(0.999);
  fig.cyclictest_p99_us = c.ran ? c.p99_us : 0.0;
  fig.overruns = run.totals.overruns;
  std::printf(
      "visvol-rtbench: %.0f s at 1 kHz, %d-segment %s rope, servo and simulated device, pack %s "
      "(%.1f MiB, tiles %.1f MiB = 1/%.0f)%s\n",
      o.seconds, o.segments, "articulated", pack_path->c_str(), static_cast<double>(ts.pack_bytes) / kMiB,
      static_cast<double>(ts.budget_bytes) / kMiB, o.tile_ratio, o.dds ? ", DDS publishing" : "");
  std::printf("scheduling: SCHED_FIFO %s, memory locked %s%s\n", run.realtime.fifo ? "yes" : "no",
              realtime.memory_locked ? "yes" : "no", run.realtime.pinned ? ", pinned" : "");
  for (const std::string& w : run.realtime.warnings) std::printf("  warning: %s\n", w.c_str());
  for (const std::string& w : realtime.warnings) std::printf("  warning: %s\n", w.c_str());
  std::printf("%-22s %9s %9s %9s %9s\n", "us", "p50", "p99", "p99.9", "max");
  std::printf("%-22s %9.0f %9.0f %9.0f %9.0f\n", "loop wake-up", run.wake_latency.percentile_us(0.5), wake_p99,
              run.wake_latency.percentile_us(0.999), run.wake_latency.max_us());
  if (c.ran) {
    std::printf("%-22s %9.0f %9.0f %9.0f %9.0f\n", "cyclictest wake-up", c.p50_us, c.p99_us, c.p999_us, c.max_us);
  } else {
    std::printf("cyclictest: %s\n", c.error.c_str());
  }
  std::printf("%-22s %9.0f %9.0f %9.0f %9.0f\n", "loop compute", run.compute.percentile_us(0.5),
              run.compute.percentile_us(0.99), run.compute.percentile_us(0.999), run.compute.max_us());
  if (c.ran && c.p99_us > 0) std::printf("wake-up p99 ratio loop/cyclictest: %.2f\n", wake_p99 / c.p99_us);
  std::printf("ticks %llu, overruns %llu, skipped deadlines %llu\n", static_cast<unsigned long long>(run.totals.ticks),
              static_cast<unsigned long long>(run.totals.overruns), static_cast<unsigned long long>(run.totals.misses));
  std::printf("loop thread after warm-up: %llu heap allocations, %lld major and %lld minor page faults\n",
              static_cast<unsigned long long>(task.allocations()),
              static_cast<long long>(run.totals.faults_after_settle.major),
              static_cast<long long>(run.totals.faults_after_settle.minor));
  std::printf("tiles: %llu loaded, %llu evicted, %llu lookups served by a coarser level\n",
              static_cast<unsigned long long>(ts.bricks_loaded), static_cast<unsigned long long>(ts.bricks_evicted),
              static_cast<unsigned long long>(f.fallbacks()));
  std::printf("resident memory: peak %.1f MiB of a %.0f MiB budget\n", static_cast<double>(rss_peak) / kMiB,
              o.budget_mib);
  if (o.json) {
    nlohmann::json j = {{"seconds", o.seconds},
                        {"segments", o.segments},
                        {"dds", o.dds},
                        {"sched_fifo", run.realtime.fifo},
                        {"ticks", run.totals.ticks},
                        {"wake_p50_us", run.wake_latency.percentile_us(0.5)},
                        {"wake_p99_us", wake_p99},
                        {"wake_p999_us", run.wake_latency.percentile_us(0.999)},
                        {"wake_max_us", run.wake_latency.max_us()},
                        {"compute_p50_us", run.compute.percentile_us(0.5)},
                        {"compute_p99_us", run.compute.percentile_us(0.99)},
                        {"overruns", run.totals.overruns},
                        {"rt_allocations", task.allocations()},
                        {"rt_major_faults", run.totals.faults_after_settle.major},
                        {"rt_minor_faults", run.totals.faults_after_settle.minor},
                        {"rss_mib", static_cast<double>(rss_peak) / kMiB},
                        {"budget_mib", o.budget_mib},
                        {"tile_budget_mib", static_cast<double>(ts.budget_bytes) / kMiB},
                        {"pack_mib", static_cast<double>(ts.pack_bytes) / kMiB}};
    if (c.ran) {
      j["cyclictest_p50_us"] = c.p50_us;
      j["cyclictest_p99_us"] = c.p99_us;
      j["cyclictest_p999_us"] = c.p999_us;
      j["cyclictest_max_us"] = c.max_us;
      j["wake_p99_ratio"] = c.p99_us > 0 ? wake_p99 / c.p99_us : 0.0;
    } else {
      j["cyclictest_p99_us"] = nullptr;
      j["cyclictest_error"] = c.error;
    }
    std::printf("%s\n", j.dump().c_str());
  }
  return 0;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The executive with and without DDS publishing, in alternating runs of one
// invocation (so that both see the same machine load), medians per figure.
int compare_dds(Options o) {
  std::vector<Figures> without, with;
  for (int r = 0; r < o.compare_rounds; ++r) {
    for (bool dds : {false, true}) {
      o.dds = dds;
      Figures f;
      std::printf("\n--- round %d of %d, %s\n", r + 1, o.compare_rounds, dds ? "publishing" : "not publishing");
      if (const int rc = run(o, f); rc != 0) return rc;
      (dds ? with : without).push_back(f);
    }
  }
  auto column = [](const std::vector<Figures>& v, double Figures::*field) {
    std::vector<double> x;
    for (const Figures& f : v) x.push_back(f.*field);
    return median(x);
  };
  struct Row {
    const char* name;
    double Figures::*field;
  };
  const Row rows[] = {
      {"loop wake-up p50", &Figures::wake_p50_us},       {"loop wake-up p99", &Figures::wake_p99_us},
      {"loop compute p50", &Figures::compute_p50_us},    {"loop compute p99", &Figures::compute_p99_us},
      {"loop compute p99.9", &Figures::compute_p999_us}, {"cyclictest p99", &Figures::cyclictest_p99_us}};
  std::printf("\nexecutive with and without DDS publishing: medians of %d alternating runs of %.0f s each\n",
              o.compare_rounds, o.seconds);
  std::printf("%-22s %12s %12s %8s\n", "us", "without DDS", "with DDS", "ratio");
  nlohmann::json j = {{"rounds", o.compare_rounds}, {"seconds", o.seconds}};
  for (const Row& row : rows) {
    const double a = column(without, row.field), b = column(with, row.field);
    std::printf("%-22s %12.0f %12.0f %8.2f\n", row.name, a, b, a > 0 ? b / a : 0.0);
    j["without_dds"][row.name] = a;
    j["with_dds"][row.name] = b;
  }
  if (o.json) std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-rtbench")) return 0;
  CLI::App app{"visvol-rtbench: the console's 1 kHz loop under load, beside cyclictest"};
  app.set_version_flag("--version", visvol::version_line("visvol-rtbench"));  // listed in --help; handled first in main
  Options o;
  app.add_option("--seconds", o.seconds, "Run time, s")->check(CLI::Range(2.0, 3600.0))->capture_default_str();
  app.add_flag("--json", o.json, "End with one JSON object");
  app.add_option("--pack", o.pack, "Field pack (default: out/sf_north.vvp, or one built from the bundled DEM)")
      ->check(CLI::ExistingFile);
  app.add_flag("--dds", o.dds, "Publish the path and device status over DDS (loopback) while running");
  app.add_option("--priority", o.priority, "SCHED_FIFO priority of the loop and of cyclictest")
      ->check(CLI::Range(1, 99))
      ->capture_default_str();
  app.add_option("--cpu", o.cpu, "Pin the loop and cyclictest to this CPU (-1: no pinning)")->capture_default_str();
  app.add_option("--segments", o.segments, "Rope segments")->check(CLI::Range(2, 1024))->capture_default_str();
  app.add_option("--tile-ratio", o.tile_ratio, "Pack size over tile budget")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--budget-mib", o.budget_mib, "Memory budget of the process, MiB")->capture_default_str();
  app.add_option("--domain", o.domain, "DDS domain for --dds")->check(CLI::Range(0u, 232u))->capture_default_str();
  app.add_option("--compare-dds", o.compare_rounds,
                 "Run N pairs of runs, without and then with DDS publishing, and print their medians side by side")
      ->check(CLI::Range(1, 100));
  visvol::decimal_numbers(app);
  CLI11_PARSE(app, argc, argv);
  if (o.compare_rounds > 0) return compare_dds(o);
  Figures unused;
  return run(o, unused);
}
