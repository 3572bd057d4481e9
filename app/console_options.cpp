#include "app/console_options.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "base/cli_numbers.hpp"
#include "base/terminal_text.hpp"
#include "base/tolerances.hpp"
#include "io/input_file.hpp"

namespace visvol::app {

namespace {

// A regular file, checked without blocking: CLI11 and the script reader open
// by name, and open() of a FIFO waits for a writer for ever.
std::string regular_file_problem(const std::string& path) {
  const Status s = check_input_file(path);
  return s.ok() ? std::string() : s.message();
}

// The configuration file's sections and the keys each holds (the long option
// names; app/systemd/console.toml documents them in this order).
const std::vector<std::pair<std::string, std::vector<std::string>>>& config_sections() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> sections = {
      {"terrain", {"pack", "terrain", "catalogue"}},
      {"session", {"seconds", "out", "quiet"}},
      {"rope", {"from", "to", "objective", "model", "segments", "max-segments", "k1", "k2", "k3", "level"}},
      {"vehicle",
       {"vehicle", "speed", "max-climb", "max-descent", "min-turn-radius", "clearance", "max-agl", "max-altitude",
        "acceptance-radius", "max-wind", "autopilot"}},
      {"observers", {"hidden-from", "visible-to", "eye-height", "max-observers"}},
      {"realtime",
       {"budget-mib", "period-us", "priority", "cpu", "no-lock", "overrun-limit", "inject-stall", "tile-margin"}},
      {"device", {"device", "can-interface", "node", "script"}},
      {"dds", {"no-dds", "domain", "dds-config", "namespace"}},
      {"thumbnails", {"thumbnail-view", "thumbnail-size", "thumbnail-max-hz"}},
  };
  return sections;
}

const std::vector<std::string>* keys_of_section(const std::string& name) {
  for (const auto& [section, keys] : config_sections()) {
    if (section == name) return &keys;
  }
  return nullptr;
}

std::string section_of_key(const std::string& key) {
  for (const auto& [section, keys] : config_sections()) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) return section;
  }
  return {};
}

std::string section_names() {
  std::string out;
  for (const auto& s : config_sections()) out += (out.empty() ? "[" : ", [") + s.first + "]";
  return out;
}

// A console configuration is a page of keys: more than this is not one.
constexpr std::size_t kMaxConfigBytes = 1 << 20;
// Arrays in a value nest no deeper than this (the deepest the options take
// is one: hidden-from = [[x, y, z], ...] is two).
constexpr int kMaxConfigNesting = 8;

// A section header's name as TOML compares it: [ session ], ["session"],
// [[session]] (which CLI11 reads as the same) and [session] are one.
std::string section_name(const std::string& header) {
  std::string name;
  for (const char c : header) {
    if (c != ' ' && c != '\t' && c != '"' && c != '\'' && c != '[' && c != ']') name += c;
  }
  return name;
}

// A key as the option it names: quotes and blanks gone, and a dotted key
// (session.seconds at the top level) by its last part.
std::string key_name(const std::string& key) {
  std::string name;
  for (const char c : key) {
    if (c == '.') {
      name.clear();
    } else if (c != ' ' && c != '\t' && c != '"' && c != '\'') {
      name += c;
    }
  }
  return name;
}

[[noreturn]] void config_refused(int line_no, const std::string& what) {
  throw CLI::ConfigError("line " + std::to_string(line_no) + ": " + what);
}

// What CLI11's reader (2.1) would get wrong, made plain or refused before it
// reads; returns the text it then reads.
// - Refused: a file over kMaxConfigBytes; brackets nested deeper than
//   kMaxConfigNesting anywhere in a value, strings included (CLI11 unquotes
//   and splits a value on commas and blanks, and reads every piece shaped
//   [...] as arrays: 100,000 levels overflowed its recursion, a segmentation
//   fault); a section or a key given twice (TOML forbids it; CLI11 kept one
//   silently), [default] (CLI11's name for the top level) and [[tables]];
//   an unclosed or a multi-line string; '#' or '\' in a string (CLI11 cuts a
//   value at '#' and reads no escapes).
// - Made plain: comments and carriage returns removed, an array over several
//   lines joined onto its key's line (CLI11 read "[rope] # note" as a key,
//   and an array opened alone on its line as a section).
std::string prechecked_config(std::istream& input) {
  std::string text;
  char chunk[4096];
  while (input.read(chunk, sizeof chunk) || input.gcount() > 0) {
    text.append(chunk, static_cast<std::size_t>(input.gcount()));
    if (text.size() > kMaxConfigBytes) {
      throw CLI::ConfigError("the file is over " + std::to_string(kMaxConfigBytes >> 10) +
                             " KiB: not a console configuration");
    }
  }
  std::vector<std::string> sections;
  std::vector<std::pair<std::string, int>> keys;  // option names given, and their lines
  std::string out, pending;                       // the text for CLI11; a line an array still continues
  int depth = 0;                                  // unquoted brackets open: the array goes on
  int nest = 0;                                   // every bracket open in the value, quoted ones too
  int pending_line = 0;
  std::size_t begin = 0;
  for (int line_no = 1; begin <= text.size(); ++line_no) {
    const std::size_t eol = std::min(text.find('\n', begin), text.size());
    const std::string raw = text.substr(begin, eol - begin);
    begin = eol + 1;
    // the line without its comment and carriage returns; strings kept whole
    std::string line;
    char quote = 0;
    bool in_value = depth > 0;  // after the key's '=' (or an array's next line)
    bool array = depth > 0;     // the value opens with '[': its unquoted brackets decide where it ends
    bool value_start = false;   // nothing but blanks since the '='
    for (std::size_t n = 0; n < raw.size(); ++n) {
      const char c = raw[n];
      if (c == '\r') continue;
      if (quote == 0 && c == '#') break;
      line += c;
      if (value_start && c != ' ' && c != '\t') {
        array = c == '[';
        value_start = false;
      }
      if (quote != 0) {
        if (c == quote) {
          quote = 0;
        } else if (c == '#' || c == '\\') {
          config_refused(line_no, std::string("'") + c +
                                      "' in a string: the console's reader cuts a value at '#' and reads no escapes");
        }
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '=' && !in_value) {
        in_value = true;
        value_start = true;
        nest = 0;
      } else if (array && c == '[') {
        ++depth;
      } else if (array && c == ']') {
        depth = std::max(depth - 1, 0);
      }
      if (in_value && (c == '[' || c == ']')) {
        nest = c == '[' ? nest + 1 : std::max(nest - 1, 0);
        if (nest > kMaxConfigNesting) {
          config_refused(line_no, "brackets nested deeper than " + std::to_string(kMaxConfigNesting) +
                                      " in a value (CLI11 reads them as arrays, quoted or not)");
        }
      }
    }
    if (quote != 0) config_refused(line_no, "a string is not closed on its line");
    if (line.find("\"\"\"") != std::string::npos || line.find("'''") != std::string::npos) {
      config_refused(line_no, "multi-line strings are not read; write the value on one line");
    }
    if (!pending.empty()) {  // an array's next line
      pending += " " + line;
      if (depth == 0) {
        out += pending + "\n";
        pending.clear();
      }
      continue;
    }
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) {
      out += "\n";
      continue;
    }
    if (line[first] == '[' && line.find('=') == std::string::npos) {
      if (line.compare(first, 2, "[[") == 0) config_refused(line_no, "arrays of tables ([[...]]) are not read");
      const std::string name = section_name(line);
      std::string lower = name;
      for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (lower == "default") {
        config_refused(line_no,
                       "unknown section [" + terminal_safe(name, 80) + "] (the sections are " + section_names() + ")");
      }
      if (std::find(sections.begin(), sections.end(), name) != sections.end()) {
        config_refused(line_no, "section [" + terminal_safe(name, 80) + "] is defined twice (a section is one table)");
      }
      sections.push_back(name);
      depth = 0;
      out += "[" + name + "]\n";
      continue;
    }
    const std::size_t equals = line.find('=');
    if (equals != std::string::npos) {
      std::string key = key_name(line.substr(0, equals));
      if (key == "o") key = "out";  // -o, as CLI11 reads a one-letter key
      for (const auto& [seen, at] : keys) {
        if (seen == key) {
          config_refused(line_no, "key '" + terminal_safe(key, 80) + "' is given twice (lines " + std::to_string(at) +
                                      " and " + std::to_string(line_no) + ")");
        }
      }
      keys.emplace_back(key, line_no);
    }
    if (depth > 0) {
      pending = line;
      pending_line = line_no;
    } else {
      out += line + "\n";
    }
  }
  if (!pending.empty()) config_refused(pending_line, "an array is not closed");
  return out;
}

// TOML (or INI) as CLI11 reads it, with the sections above: a key in its own
// section (or at the top level, as before sections) is the option it names;
// a key in another section, an unknown section or a nested one is refused,
// naming it.
class SectionedConfig final : public CLI::ConfigTOML {
 public:
  std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
    std::istringstream checked(prechecked_config(input));
    std::vector<CLI::ConfigItem> read = CLI::ConfigTOML::from_config(checked);
    std::vector<CLI::ConfigItem> out;
    for (CLI::ConfigItem& item : read) {
      if (item.parents.empty()) {
        out.push_back(std::move(item));
        continue;
      }
      const std::string section = CLI::detail::join(item.parents, ".");
      const std::vector<std::string>* keys = keys_of_section(section);
      if (keys == nullptr) {
        throw CLI::ConfigError("unknown section [" + section + "] (the sections are " + section_names() + ")");
      }
      if (item.name == "++" || item.name == "--") continue;  // CLI11's marks of a section's start and end
      if (std::find(keys->begin(), keys->end(), item.name) == keys->end()) {
        const std::string home = section_of_key(item.name);
        throw CLI::ConfigError(home.empty()
                                   ? "unknown key '" + item.name + "' in [" + section + "]"
                                   : "key '" + item.name + "' belongs in [" + home + "], not [" + section + "]");
      }
      item.parents.clear();
      out.push_back(std::move(item));
    }
    return out;
  }
};

}  // namespace

std::string config_error_text(const std::string& message) {
  const std::string prefix = "INI was not able to parse ";
  if (message.rfind(prefix, 0) != 0) return message;
  std::string key = message.substr(prefix.size());
  const std::string section_marker = ".++";
  if (key.size() > section_marker.size() && key.compare(key.size() - 3, 3, section_marker) == 0) {
    return "unknown section [" + key.substr(0, key.size() - 3) + "] (the sections are " + section_names() + ")";
  }
  return "unknown key '" + key + "' (keys are the long option names without the dashes)";
}

void add_console_options(CLI::App& app, ConsoleOptions& o) {
  // checked as soon as it is parsed: CLI11 reads it before any other check
  app.config_formatter(std::make_shared<SectionedConfig>());
  app.set_config("--config", "",
                 "Read options from this TOML (or INI) file: the long option names as keys, at the top level or in "
                 "their sections ([terrain], [session], [rope], [vehicle], [observers], [realtime], [device], [dds], "
                 "[thumbnails]; /etc/visvol/console.toml shows each)")
      ->check(CLI::Validator([](std::string& path) { return regular_file_problem(path); }, "FILE"))
      ->trigger_on_parse();
  // a key the console does not know is a mistake to name, not to skip
  app.allow_config_extras(CLI::config_extras_mode::error);
  app.add_option("--pack", o.pack, "Field pack to plan in (visvol build ... -o PACK)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--terrain", o.terrains,
                 "Another preloaded pack that a switch-terrain command (by pack id: the file name without its "
                 "extension) may move the console to; repeatable")
      ->check(CLI::ExistingFile);
  app.add_option("--catalogue", o.catalogue,
                 "Folder of preloaded packs (ID.vvp): each verified off the loop's thread, watched for packs "
                 "added, replaced or removed; switch-terrain takes any verified one by its ID")
      ->check(CLI::ExistingDirectory);
  app.add_option("--seconds", o.seconds, "Run this long, s (0: until Ctrl-C or SIGTERM)")->capture_default_str();
  app.add_flag("--quiet", o.quiet,
               "No progress lines (the memory table at start, a line a second); warnings, errors and the closing "
               "summary stay");
  app.add_option("-o,--out", o.out, "Directory for the path, health log and summary")->capture_default_str();
  app.add_option("--from", o.from,
                 "Rope start X Y Z (pack CRS, m; inside the pack's planning bounds; default: a tenth in from their "
                 "west edge, half way north, 150 m up)")
      ->expected(3);
  app.add_option("--to", o.to, "Rope end X Y Z (default: a tenth in from the planning bounds' east edge, 150 m up)")
      ->expected(3);
  app.add_option("--objective", o.objective, "hide or show")
      ->check(CLI::IsMember({"hide", "show"}))
      ->capture_default_str();
  app.add_option("--model", o.model, "articulated or spring")
      ->check(CLI::IsMember({"articulated", "spring"}))
      ->capture_default_str();
  app.add_option("--segments", o.segments, "Rope segments at start")->capture_default_str();
  app.add_option("--max-segments", o.max_segments, "Rope segments reserved (set-segments may go up to this)")
      ->capture_default_str();
  cli::add_envelope_options(app, o.envelope);
  app.add_option("--hidden-from", o.hidden_from,
                 "Stay hidden from an observer standing at X Y Z (pack CRS, m; at or above the terrain); repeatable, "
                 "at most 256")
      ->expected(3)
      ->allow_extra_args(false);
  app.add_option("--visible-to", o.visible_to, "Stay visible to an observer at X Y Z; repeatable, at most 256")
      ->expected(3)
      ->allow_extra_args(false);
  app.add_option("--eye-height", o.eye_height_m, "Observers' eyes above the points named (options and commands), m")
      ->capture_default_str();
  app.add_option("--max-observers", o.max_observers,
                 "Hidden-from and visible-to points a constraint set may name, 0..512 (each kind is folded into one "
                 "hull of the rope's level: three sets of two are reserved whatever the number; default: 512 "
                 "where they fit in a quarter of --budget-mib, else only those given)")
      // checked as given: -1, the default's own mark, was taken when typed
      ->check(CLI::Range(0, kMaxObservers));
  app.add_option("--k1", o.k1, "Visibility gain (sign from the objective)")->capture_default_str();
  app.add_option("--k2", o.k2, "Terrain force field gain")->capture_default_str();
  app.add_option("--k3", o.k3, "Operator pull gain")->capture_default_str();
  app.add_option("--budget-mib", o.budget_mib, "Memory budget of the whole process, MiB; tiles get what is left")
      ->capture_default_str();
  app.add_option("--period-us", o.period_us, "Loop period, us")->capture_default_str();
  app.add_option("--priority", o.priority, "SCHED_FIFO priority of the loop (0: none)")->capture_default_str();
  app.add_option("--cpu", o.cpu, "Pin the loop to this CPU (-1: no pinning)")->capture_default_str();
  app.add_flag("!--no-lock", o.lock_memory, "Do not lock memory (mlockall)");
  app.add_option("--overrun-limit", o.overrun_limit, "Overruns in a row before the haptic safe state")
      ->capture_default_str();
  app.add_option("--level", o.level, "Level of detail the rope runs on (0: finest)")->capture_default_str();
  app.add_option("--inject-stall", o.inject_stall,
                 "Fault injection, for supervision tests: the loop stops ticking AT_S s after it started, for "
                 "FOR_S s (systemd's watchdog pings stop), once")
      ->expected(2)
      ->type_name("AT_S FOR_S");
  decimal_reals(app.get_option("--inject-stall"));
  app.add_option("--device", o.device, "Haptic device: sim (simulated, in-process bus), socketcan, none")
      ->check(CLI::IsMember({"sim", "socketcan", "none"}))
      ->capture_default_str();
  app.add_option("--can-interface", o.can_interface, "CAN interface for --device socketcan (e.g. can0, vcan0)");
  app.add_option("--node", o.node, "Device node id, 1..127")->capture_default_str();
  app.add_option("--script", o.script,
                 "Simulated operator: builtin (grab and pull), none, or a visvol-hapticsim script")
      ->check(CLI::Validator(
          [](std::string& v) { return v == "builtin" || v == "none" ? std::string() : regular_file_problem(v); },
          "builtin|none|FILE"))
      ->capture_default_str();
  app.add_flag("!--no-dds", o.dds, "Do not publish or take commands over DDS");
  app.add_option("--domain", o.domain, "DDS domain id")->check(CLI::Range(0u, 232u))->capture_default_str();
  app.add_option("--dds-config", o.dds_config, "Cyclone DDS XML configuration (default: loopback only)")
      ->check(CLI::ExistingFile);
  app.add_option("--namespace", o.dds_namespace, "DDS topic namespace");
  app.add_option("--tile-margin", o.tile_margin_m, "Tiles kept resident around the rope, m")->capture_default_str();
  app.add_option("--thumbnail-view", o.thumbnail_view,
                 "Thumbnails when the rope comes to rest (DDS and thumbnail.png): oblique, top, volume, slice, none")
      ->check(CLI::IsMember({"oblique", "top", "volume", "slice", "none"}))
      ->capture_default_str();
  app.add_option("--thumbnail-size", o.thumbnail_size, "Thumbnail size WxH, pixels")->capture_default_str();
  app.add_option("--thumbnail-max-hz", o.thumbnail_max_hz, "Thumbnails a second at most")->capture_default_str();
  decimal_numbers(app);
}

Result<std::pair<int, int>> parse_thumbnail_size(const std::string& text) {
  // strtol, not sscanf's %d (undefined past INT_MAX): each side's digits, bounded
  auto side = [](const char* from, char** end) {
    if (!std::isdigit(static_cast<unsigned char>(*from))) return -1L;
    errno = 0;
    const long v = std::strtol(from, end, 10);
    return errno == 0 ? v : -1L;
  };
  char* end = nullptr;
  const long w = side(text.c_str(), &end);
  long h = -1;
  if (w >= 0 && (*end == 'x' || *end == 'X')) h = side(end + 1, &end);
  if (w < 32 || h < 32 || w > 4096 || h > 4096 || *end != '\0') {
    return invalid_argument("--thumbnail-size: '" + text + "' is not WxH with sides 32..4096 pixels");
  }
  return std::pair{static_cast<int>(w), static_cast<int>(h)};
}

namespace {

std::string metres(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g m", v);
  return text;
}

// The ceilings given as options: finite, above the clearance (the vehicle
// check that follows names the vehicle; these name the options).
Status validate_ceilings(const cli::EnvelopeOptions& e) {
  const double clearance = e.clearance_m.value_or(rt::VehicleEnvelope().clearance_m);
  if (e.clearance_m && !(*e.clearance_m >= 0 && *e.clearance_m <= 10000)) {
    return invalid_argument("--clearance: must be in 0..10000 m");
  }
  if (e.max_agl_m) {
    const double v = *e.max_agl_m;
    if (!(std::isfinite(v) && v > 0 && v <= 10000)) return invalid_argument("--max-agl: must be in (0, 10000] m");
    if (!(v > clearance)) {
      return invalid_argument("--max-agl: " + metres(v) + " is not above --clearance " + metres(clearance) +
                              ": no height is allowed");
    }
  }
  if (e.max_altitude_m &&
      !(std::isfinite(*e.max_altitude_m) && std::fabs(*e.max_altitude_m) <= rt::VehicleEnvelope::kMaxAltitudeRangeM)) {
    return invalid_argument("--max-altitude: must be a height in -100000..100000 m");
  }
  return {};
}

// The observers: X Y Z each, finite, at most 256 of a kind and no more than
// --max-observers allows (where/whether inside the pack: at start-up).
Status validate_observers(const ConsoleOptions& o) {
  for (const auto& [name, points] : {std::pair{"--hidden-from", &o.hidden_from}, {"--visible-to", &o.visible_to}}) {
    if (points->size() > static_cast<std::size_t>(kMaxObserversPerKind)) {
      return invalid_argument(std::string(name) + ": at most " + std::to_string(kMaxObserversPerKind) + " points");
    }
    for (const std::vector<double>& p : *points) {
      if (p.size() != 3 || !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        return invalid_argument(std::string(name) + ": needs X Y Z, three finite numbers (m)");
      }
    }
  }
  if (!(std::isfinite(o.eye_height_m) && o.eye_height_m >= 0 && o.eye_height_m <= 10000)) {
    return invalid_argument("--eye-height: must be in 0..10000 m");
  }
  if (o.max_observers < -1 || o.max_observers > kMaxObservers) {
    return invalid_argument("--max-observers: must be in 0.." + std::to_string(kMaxObservers));
  }
  const std::size_t given = o.hidden_from.size() + o.visible_to.size();
  if (o.max_observers >= 0 && given > static_cast<std::size_t>(o.max_observers)) {
    return invalid_argument("--max-observers: " + std::to_string(o.max_observers) + " is fewer than the " +
                            std::to_string(given) + " --hidden-from and --visible-to points given");
  }
  // one point both ways: no path is hidden from it and in its sight
  for (const std::vector<double>& h : o.hidden_from) {
    for (const std::vector<double>& v : o.visible_to) {
      if (same_point(h[0], h[1], h[2], v[0], v[1], v[2])) {
        return invalid_argument(
            "--hidden-from and --visible-to name the same point: no path is both hidden from it "
            "and in its sight");
      }
    }
  }
  return {};
}

}  // namespace

Status validate(const ConsoleOptions& o) {
  auto bad = [](const std::string& what) { return invalid_argument(what); };
  if (!(o.seconds >= 0 && o.seconds <= 1e7)) return bad("--seconds: must be in 0..1e7 s");
  if (o.segments < 2 || o.segments > o.max_segments) {
    return bad("--segments: " + std::to_string(o.segments) + " must be in 2..--max-segments (" +
               std::to_string(o.max_segments) + ")");
  }
  if (o.max_segments < 2 || o.max_segments > 4096) return bad("--max-segments: must be in 2..4096");
  VISVOL_RETURN_IF_ERROR(validate_ceilings(o.envelope));
  if (Result<rt::VehicleEnvelope> v = resolve_vehicle(o); !v.ok()) return v.status();
  VISVOL_RETURN_IF_ERROR(validate_observers(o));
  for (const auto& [name, v] : {std::pair{"--k1", o.k1}, {"--k2", o.k2}, {"--k3", o.k3}}) {
    if (!(std::isfinite(v) && v >= 0 && v <= 1e6)) return bad(std::string(name) + ": must be in 0..1e6");
  }
  if (!(o.budget_mib >= 16 && o.budget_mib <= 1 << 20)) return bad("--budget-mib: must be in 16..1048576 MiB");
  if (!(o.period_us >= 100 && o.period_us <= 100000)) return bad("--period-us: must be in 100..100000 us");
  if (o.node < 1 || o.node > 127) return bad("--node: must be in 1..127");
  if (o.device == "socketcan" && o.can_interface.empty()) {
    return bad("--device socketcan needs --can-interface (e.g. can0 or vcan0)");
  }
  if (!(o.tile_margin_m >= 0 && o.tile_margin_m <= 1e5)) return bad("--tile-margin: must be in 0..100000 m");
  if (!o.inject_stall.empty()) {
    if (o.inject_stall.size() != 2) return bad("--inject-stall: needs AT_S FOR_S");
    if (!(o.inject_stall[0] >= 0 && o.inject_stall[0] <= 1e7)) return bad("--inject-stall: AT_S must be in 0..1e7 s");
    if (!(o.inject_stall[1] > 0 && o.inject_stall[1] <= 60)) return bad("--inject-stall: FOR_S must be in (0, 60] s");
  }
  for (const auto& [name, p] : {std::pair{"--from", &o.from}, std::pair{"--to", &o.to}}) {
    if (p->empty()) continue;
    if (p->size() != 3) return bad(std::string(name) + ": needs X Y Z");
    for (double v : *p) {
      if (!std::isfinite(v)) return bad(std::string(name) + ": X Y Z must be finite (m, pack CRS)");
    }
  }
  if (auto size = parse_thumbnail_size(o.thumbnail_size); !size.ok()) return size.status();
  if (!(o.thumbnail_max_hz > 0 && o.thumbnail_max_hz <= 50)) return bad("--thumbnail-max-hz: must be in (0, 50]");
  return {};
}

Result<rt::VehicleEnvelope> resolve_vehicle(const ConsoleOptions& o) { return cli::resolve_envelope(o.envelope); }

}  // namespace visvol::app
