// visvol-hapticsim: a simulated haptic device on a CAN interface (vcan0 on a
// hardware-in-the-loop rig), driven by an operator script with fault injection.
//
// Exit status: 0 success, 1 a failure while running, 2 bad arguments or input
// (with a one-line reason on stderr). At exit it prints a one-line JSON
// summary on stdout (or into --summary FILE).
#include <time.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

#include "base/arguments.hpp"
#include "base/cli_numbers.hpp"
#include "base/version.hpp"
#include "drivers/can/socketcan_bus.hpp"
#include "drivers/hapticsim/script.hpp"
#include "drivers/hapticsim/sim_device.hpp"
#include "io/atomic_file.hpp"

namespace {

using visvol::Status;
using namespace visvol::hapticsim;

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr std::int64_t kTickNs = 1'000'000;
constexpr std::int64_t kMaxLagNs = 50'000'000;  // further behind: skip ahead instead of bursting

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "used from a signal handler");

extern "C" void on_signal(int) { g_stop.store(true); }

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int usage_error(const std::string& message) {
  std::fprintf(stderr, "visvol-hapticsim: %s\n", message.c_str());
  return kExitUsage;
}

const char* kFooter = R"(Script (--script FILE): one event per line, "TIME ACTION [ARGS]", TIME in s
from the start, non-decreasing; distances in device mm (x right, y up, z toward
the operator); '#' starts a comment.
  T hold | let-go            the hand takes the handle / lets it move freely
  T move X Y Z DUR           the hand moves to (X, Y, Z) over DUR s
  T grab | release           press / release the grasp button (button 1)
  T clutch on|off            press / release the clutch button (button 2)
  T mode on|off              press / release the mode button (button 3: pull / spool)
  T pull DX DY DZ DUR        grab, then move by (DX, DY, DZ) over DUR s
  T drag DX DY DZ DUR [S]    spool mode: grab and drag by (DX, DY, DZ) in strokes of
                             at most S mm (60), re-centring with the clutch held
  T drop F                   drop the fraction F of frames (both directions)
  T silent DUR               send and receive nothing for DUR s
  T garbage N                send N frames of random identifiers, lengths, bytes
  T wrong-length DUR         send own frames with wrong lengths for DUR s
  T freeze DUR               repeat the last position frame unchanged for DUR s
  T reboot [DUR]             power off for DUR s (0.2), then boot again
  T bus-off DUR              error frame bus-off, silence, error frame restarted
  T emergency KIND DUR       over-current | over-temperature | amplifier | encoder
  T end                      stop
Example: visvol-hapticsim -i vcan0 --node 1 --script pull.txt --duration 5
Exit status: 0 done, 1 failure while running, 2 bad arguments or input.)";

struct Options {
  std::string interface;
  int node = 1;
  std::string script_path;
  double duration_s = 0.0;
  double boot_delay_s = 0.0;
  std::string summary_path;
  bool check_only = false;
  SimConfig sim;
  double watchdog_ms = 10.0;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("-i,--interface", o.interface, "CAN interface, e.g. vcan0 (required unless --check)");
  app.add_option("--node", o.node, "CANopen node id of the device, 1..127")->capture_default_str();
  app.add_option("--script", o.script_path, "operator motions and faults (format below)");
  app.add_option("--duration", o.duration_s, "stop after this many seconds (0: at the script's end, or a signal)")
      ->capture_default_str();
  app.add_option("--boot-delay", o.boot_delay_s, "stay powered off for this many seconds first")->capture_default_str();
  app.add_option("--drop", o.sim.drop_fraction, "drop this fraction of frames in both directions, 0..1")
      ->capture_default_str();
  app.add_option("--seed", o.sim.seed, "random seed for drops and garbage")->capture_default_str();
  app.add_option("--mass-kg", o.sim.mass_kg, "apparent handle mass, kg")->capture_default_str();
  app.add_option("--viscous", o.sim.viscous_n_s_per_m, "viscous friction, N s/m")->capture_default_str();
  app.add_option("--coulomb", o.sim.coulomb_n, "dry friction, N")->capture_default_str();
  app.add_option("--peak-force", o.sim.peak_force_n, "motor force saturation, N")->capture_default_str();
  app.add_option("--watchdog-ms", o.watchdog_ms, "zero the force after this long without a command, ms")
      ->capture_default_str();
  app.add_option("--summary", o.summary_path, "write the JSON summary here instead of stdout");
  app.add_flag("--check", o.check_only, "only check the arguments and the script, then exit");
  app.footer(kFooter);
}

std::string summary_json(const Options& o, const SimDevice& d, const visvol::can::CanCounters& bus, double run_s) {
  const SimCounters& c = d.counters();
  char buf[2048];
  std::snprintf(buf, sizeof(buf),
                "{\"node\":%d,\"run_s\":%.3f,\"frames_sent\":%llu,\"send_failures\":%llu,\"tx_dropped\":%llu,"
                "\"rx_dropped\":%llu,\"rx_ignored\":%llu,\"commands\":%llu,\"command_gaps\":%llu,\"malformed\":%llu,"
                "\"nmt_commands\":%llu,\"watchdog_trips\":%llu,\"saturated_steps\":%llu,\"force_steps\":%llu,"
                "\"operational_steps\":%llu,\"boots\":%llu,\"emergencies\":%llu,\"garbage_sent\":%llu,"
                "\"bus_off_events\":%llu,\"max_force_n\":%.4f,\"max_commanded_n\":%.4f,\"first_operational_s\":%.4f,"
                "\"bus_received\":%llu,\"bus_dropped\":%llu,\"final_nmt_state\":%u}",
                o.node, run_s, static_cast<unsigned long long>(c.frames_sent),
                static_cast<unsigned long long>(c.send_failures), static_cast<unsigned long long>(c.tx_dropped),
                static_cast<unsigned long long>(c.rx_dropped), static_cast<unsigned long long>(c.rx_ignored),
                static_cast<unsigned long long>(c.commands), static_cast<unsigned long long>(c.command_gaps),
                static_cast<unsigned long long>(c.malformed), static_cast<unsigned long long>(c.nmt_commands),
                static_cast<unsigned long long>(c.watchdog_trips), static_cast<unsigned long long>(c.saturated_steps),
                static_cast<unsigned long long>(c.force_steps), static_cast<unsigned long long>(c.operational_steps),
                static_cast<unsigned long long>(c.boots), static_cast<unsigned long long>(c.emergencies),
                static_cast<unsigned long long>(c.garbage_sent), static_cast<unsigned long long>(c.bus_off_events),
                c.max_force_n, c.max_commanded_n,
                c.first_operational_ns < 0 ? -1.0 : static_cast<double>(c.first_operational_ns) / 1e9,
                static_cast<unsigned long long>(bus.received), static_cast<unsigned long long>(bus.dropped),
                static_cast<unsigned>(d.nmt_state()));
  return buf;
}

int run(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-hapticsim")) return 0;
  if (const int empty = visvol::first_empty_argument(argc, argv); empty > 0) {
    std::fprintf(stderr, "visvol-hapticsim: %s (try --help)\n", visvol::empty_argument_problem(argv, empty).c_str());
    return 2;
  }
  CLI::App app{
      "visvol-hapticsim: a simulated 3-DOF haptic device (Phantom Premium 1.5 stand-in) on a CAN\n"
      "interface: handle dynamics, 0.01 mm encoder, 8.5 N saturation, 10 ms command watchdog,\n"
      "scripted operator motions and fault injection. Protocol: drivers/haptic/protocol.md."};
  app.set_version_flag("--version",
                       visvol::version_line("visvol-hapticsim"));  // listed in --help; handled first in main
  Options o;
  add_options(app, o);
  visvol::decimal_numbers(app);  // "010" is ten, not octal eight
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      std::printf("%s", app.help().c_str());
      return kExitOk;
    }
    return usage_error(std::string(e.what()) + " (try --help)");
  }

  // Arguments and the script.
  if (o.node < visvol::haptic::kMinNodeId || o.node > visvol::haptic::kMaxNodeId) {
    return usage_error("--node " + std::to_string(o.node) + " is outside 1..127");
  }
  if (!(o.duration_s >= 0.0 && o.duration_s <= 1e6)) return usage_error("--duration must lie in [0, 1e6] s");
  if (!(o.boot_delay_s >= 0.0 && o.boot_delay_s <= 3600.0)) return usage_error("--boot-delay must lie in [0, 3600] s");
  if (!(o.watchdog_ms >= 1.0 && o.watchdog_ms <= 10000.0))
    return usage_error("--watchdog-ms must lie in [1, 10000] ms");
  o.sim.node_id = static_cast<std::uint8_t>(o.node);
  o.sim.boot_delay_ns = static_cast<std::int64_t>(o.boot_delay_s * 1e9);
  o.sim.command_timeout_ns = static_cast<std::int64_t>(o.watchdog_ms * 1e6);
  if (Status s = SimDevice::validate(o.sim); !s.ok()) return usage_error(s.message());
  Script script;
  if (!o.script_path.empty()) {
    auto loaded = load_script(o.script_path, o.sim.workspace_half_mm);
    if (!loaded.ok()) return usage_error(loaded.status().message());
    script = std::move(loaded).value();
  }
  if (o.check_only) {
    std::printf("visvol-hapticsim: arguments ok; script: %zu events, over after %.3f s\n", script.events.size(),
                script.end_s);
    return kExitOk;
  }
  if (o.interface.empty()) return usage_error("--interface is required (e.g. -i vcan0)");

  // The bus: this device's command identifier and NMT only.
  visvol::can::SocketCanConfig bus_config;
  bus_config.interface = o.interface;
  bus_config.filters = {
      {visvol::haptic::frame_id(visvol::haptic::MessageKind::command, o.sim.node_id), visvol::can::kStandardIdMask},
      {visvol::haptic::kNmtId, visvol::can::kStandardIdMask}};
  bus_config.error_frames = false;
  auto bus = visvol::can::SocketCanBus::open(bus_config);
  if (!bus.ok()) {
    // A wrong interface name is bad input; a kernel without SocketCAN is a failure here.
    if (bus.status().code() == visvol::Errc::invalid_argument) return usage_error(bus.status().message());
    std::fprintf(stderr, "visvol-hapticsim: %s\n", bus.status().message().c_str());
    return kExitFailure;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  // The 1 kHz loop: absolute deadlines; skip ahead rather than burst after a stall.
  const std::int64_t start_ns = mono_ns();
  auto created = SimDevice::create(o.sim, **bus, start_ns);
  if (!created.ok()) return usage_error(created.status().message());
  SimDevice device = std::move(created).value();
  Player player(script);
  std::int64_t next_ns = start_ns;
  double t_s = 0.0;
  while (!g_stop.load()) {
    const std::int64_t now_ns = mono_ns();
    t_s = static_cast<double>(now_ns - start_ns) / 1e9;
    player.advance(t_s, now_ns, device);
    device.step(now_ns);
    if ((o.duration_s > 0.0 && t_s >= o.duration_s) || player.ended()) break;
    next_ns += kTickNs;
    if (now_ns - next_ns > kMaxLagNs) next_ns = now_ns + kTickNs;
    timespec deadline{static_cast<time_t>(next_ns / 1'000'000'000), static_cast<long>(next_ns % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR && !g_stop.load()) {
    }
  }

  const std::string summary = summary_json(o, device, (*bus)->counters(), t_s) + "\n";
  if (o.summary_path.empty()) {
    std::fputs(summary.c_str(), stdout);
    return kExitOk;
  }
  if (const Status written = visvol::write_file_atomically(o.summary_path, summary); !written.ok()) {
    std::fprintf(stderr, "visvol-hapticsim: cannot write the summary: %s\n", written.message().c_str());
    // a path that cannot be an output is bad input; a full disk is a failure
    return written.code() == visvol::Errc::invalid_argument ? kExitUsage : kExitFailure;
  }
  return kExitOk;
}

}  // namespace

// Anything thrown (memory, mostly) ends the process with a message and a
// status, never with std::terminate's abort.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "visvol-hapticsim: internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "visvol-hapticsim: internal error (unknown exception)\n");
  }
  return kExitFailure;
}
