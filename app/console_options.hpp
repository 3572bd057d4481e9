// What the console is told to do: command-line options, optionally from a
// configuration file (INI or TOML, the same names as the long options).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/mission_options.hpp"
#include "base/status.hpp"
#include "rt/rope/vehicle.hpp"

namespace CLI {
class App;  // <CLI/CLI.hpp> only where the options are parsed: it is the heaviest header
}

namespace visvol::app {

struct ConsoleOptions {
  std::string pack;
  std::vector<std::string> terrains;  // other packs a switch-terrain command may move to
  double seconds = 0;                 // 0: until SIGINT or SIGTERM
  std::string out = "out/console";    // outputs
  // The planning problem (pack CRS, metres); empty: across the pack west to east.
  std::vector<double> from, to;
  std::string objective = "hide";
  std::string model = "articulated";
  int segments = 128;
  int max_segments = 256;
  // The vehicle and its envelope, with the options `visvol plan` takes
  // (--vehicle, --speed, --max-climb, --max-descent, --min-turn-radius,
  // --clearance, --max-agl, --max-altitude; the ceilings: none when absent).
  // The paths the console sends are fitted into it (app/flyable_path.hpp).
  cli::EnvelopeOptions envelope;
  // The observers, as `visvol plan` names them (pack CRS, metres): points to
  // stay hidden from and visible to (X Y Z each, at most 256 of a kind), their
  // observers' eyes above them.
  std::vector<std::vector<double>> hidden_from, visible_to;
  double eye_height_m = 2.0;
  int max_observers = -1;  // observers a set may name; -1: as the budget allows (see add_console_options)
  double k1 = 1, k2 = 1, k3 = 1;
  // Real time.
  double budget_mib = 256;
  double period_us = 1000;
  int priority = 80;
  int cpu = -1;
  bool lock_memory = true;
  std::string catalogue;  // folder of packs a switch-terrain may take (empty: none)
  int overrun_limit = 5;
  int level = 0;
  std::vector<double> inject_stall;  // fault injection: AT_S FOR_S, the loop stops ticking (empty: none)
  // Haptic device.
  std::string device = "sim";  // sim | socketcan | none
  std::string can_interface;   // socketcan
  int node = 1;
  std::string script = "builtin";  // sim: builtin | none | FILE
  bool quiet = false;              // no progress lines on standard error
  // DDS.
  bool dds = true;
  std::uint32_t domain = 0;
  std::string dds_config;  // empty: the built-in loopback configuration
  std::string dds_namespace;
  // Tiles.
  double tile_margin_m = 1000;
  // Thumbnails (renderer thread).
  std::string thumbnail_view = "oblique";  // oblique | top | volume | slice | none
  std::string thumbnail_size = "256x256";  // WxH, pixels
  double thumbnail_max_hz = 1.0;
  // Set by the console itself for a session after a terrain switch (not options).
  int session = 1;
  std::string switched_from;       // the previous session's pack id
  std::string switched_from_path;  // and its file, to go back to (a catalogue's pack is in no list here)
  std::string switch_failed;       // "PACKID: why" when a switch to it failed and this session came back
};

// "WxH" in pixels, each side 32..4096; invalid_argument naming the option.
Result<std::pair<int, int>> parse_thumbnail_size(const std::string& text);

// Registers the options (with --help texts, units and defaults) on `app`.
// CLI11's message for a configuration key it does not know ("INI was not
// able to parse KEY", "SECTION.++" for a [section] line) as a user reads it;
// any other message unchanged.
std::string config_error_text(const std::string& message);

void add_console_options(CLI::App& app, ConsoleOptions& o);
// Checks what CLI11 cannot: combinations and ranges. Names the option.
Status validate(const ConsoleOptions& o);

// The vehicle (preset or file) with the options' overrides, validated.
Result<rt::VehicleEnvelope> resolve_vehicle(const ConsoleOptions& o);

// Most observers of a kind, and of both kinds together, a console holds (as
// rt::kMaxObserversPerKind; console.cpp checks they agree).
inline constexpr int kMaxObserversPerKind = 256;
inline constexpr int kMaxObservers = 2 * kMaxObserversPerKind;

}  // namespace visvol::app
