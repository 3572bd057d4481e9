// visvol-echo: prints what a visvol console publishes and sends it commands.
//
//   visvol-echo [--domain N] [--config FILE] [--namespace NS] SUBCOMMAND
//     watch | path | health   print messages as they arrive
//     command KIND ARGS...    send one command, print its acknowledgement
//     topics                  print the topics, types and QoS
//
// Exit status: 0 success (a command accepted), 1 a failure while working (a
// command rejected, no answer, nothing received in time), 2 bad arguments.
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "base/arguments.hpp"
#include "base/cli_numbers.hpp"
#include "base/version.hpp"
#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "drivers/dds/topics.hpp"
#include "format.hpp"

namespace {

using namespace visvol;
using namespace visvol::dds;
using namespace visvol::msg;

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

std::atomic<bool> g_interrupted{false};
extern "C" void on_signal(int) { g_interrupted.store(true); }

struct Common {
  std::uint32_t domain = 0;
  bool json = false;        // one JSON object per line instead of key=value text
  std::string config_file;  // empty: the built-in loopback configuration
  std::string ns;
};

struct WatchOptions {
  std::vector<std::string> topics = {"path", "health"};
  std::size_t count = 0;   // 0: until interrupted
  double timeout_s = 0.0;  // 0: none
  bool vertices = false;
};

struct CommandOptions {
  std::string kind;
  std::string source;
  bool source_given = false;              // --source "" is an error, not the default
  std::optional<std::uint64_t> sequence;  // default: milliseconds since 1970
  double timeout_s = 5.0;
  bool wait_applied = false;
  std::vector<double> numbers;  // endpoints, weights, stiffness
  std::string word;             // objective, model, pack id
  std::uint32_t segments = 0;
  std::vector<std::string> hidden_from, visible_to;
  std::vector<double> clearances, max_agls, max_altitudes;  // m; one each (the console refuses more)
};

int usage_error(const std::string& message) {
  std::fprintf(stderr, "visvol-echo: %s (try --help)\n", message.c_str());
  return kExitUsage;
}

int failure(const std::string& message) {
  std::fprintf(stderr, "visvol-echo: %s\n", message.c_str());
  return kExitFailure;
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

// A number from the command line that must be finite.
const CLI::Validator kFinite(
    [](std::string& text) -> std::string {
      // decimal only: strtod also reads 0x10 as sixteen
      if (!visvol::is_decimal_number(text) && !visvol::is_non_finite_word(text)) {
        return "'" + text + "' is not a decimal number";
      }
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
      return std::string();
    },
    "FINITE", "finite");

// "X,Y,Z" in metres.
Result<WorldPoint> parse_point(const std::string& option, const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) {
    std::string copy = part;
    if (!kFinite(copy).empty()) break;
    v.push_back(std::strtod(part.c_str(), nullptr));
  }
  if (v.size() != 3) {
    return invalid_argument(option + " '" + text + "': expected X,Y,Z (three finite numbers, m)");
  }
  return WorldPoint{v[0], v[1], v[2]};
}

Result<std::unique_ptr<Participant>> open(const Common& common) {
  ParticipantConfig config;
  config.domain_id = common.domain;
  config.topic_namespace = common.ns;
  if (common.config_file.empty()) {
    config.cyclone_xml = std::string(loopback_config());
  } else {
    Result<std::string> xml = read_cyclone_config(common.config_file);
    if (!xml.ok()) return xml.status();
    config.cyclone_xml = *xml;
  }
  return Participant::create(config);
}

// watch ----------------------------------------------------------------------

const std::map<std::string, Topic>& watchable() {
  static const std::map<std::string, Topic> topics = {
      {"path", Topic::path_update},
      {"health", Topic::health},
      {"device", Topic::device_status},
      {"terrain", Topic::terrain},
      {"thumbnail", Topic::thumbnail},
      {"acks", Topic::command_ack},
      {"catalogue", Topic::terrain_catalogue},
  };
  return topics;
}

// Prints each message of one reader; returns how many it printed.
std::size_t print_all(Topic topic, const Reader& reader, bool vertices, bool json) {
  std::size_t printed = 0;
  const auto line = [&](const std::string& text) {
    std::printf("%s\n", text.c_str());
    ++printed;
  };
  switch (topic) {
    case Topic::path_update:
      (void)reader.take<visvol_msgs_msg_dds__PathUpdate_>([&](const auto& m, const dds_sample_info_t&) {
        line(json ? echo::json_path_update(m, vertices) : echo::format_path_update(m, vertices));
      });
      break;
    case Topic::health:
      (void)reader.take<visvol_msgs_msg_dds__LoopHealth_>(
          [&](const auto& m, const dds_sample_info_t&) { line(json ? echo::json_health(m) : echo::format_health(m)); });
      break;
    case Topic::device_status:
      (void)reader.take<visvol_msgs_msg_dds__DeviceStatus_>([&](const auto& m, const dds_sample_info_t&) {
        line(json ? echo::json_device_status(m) : echo::format_device_status(m));
      });
      break;
    case Topic::terrain:
      (void)reader.take<visvol_msgs_msg_dds__TerrainInfo_>([&](const auto& m, const dds_sample_info_t&) {
        line(json ? echo::json_terrain(m) : echo::format_terrain(m));
      });
      break;
    case Topic::terrain_catalogue:
      (void)reader.take<visvol_msgs_msg_dds__TerrainCatalogue_>([&](const auto& m, const dds_sample_info_t&) {
        line(json ? echo::json_catalogue(m) : echo::format_catalogue(m));
      });
      break;
    case Topic::thumbnail:
      (void)reader.take<sensor_msgs_msg_dds__CompressedImage_>([&](const auto& m, const dds_sample_info_t&) {
        line(json ? echo::json_thumbnail(m) : echo::format_thumbnail(m));
      });
      break;
    case Topic::command_ack:
      (void)reader.take<visvol_msgs_msg_dds__CommandAck_>(
          [&](const auto& m, const dds_sample_info_t&) { line(json ? echo::json_ack(m) : echo::format_ack(m)); });
      break;
    default: break;
  }
  if (printed > 0) std::fflush(stdout);
  return printed;
}

int run_watch(const Common& common, const WatchOptions& options) {
  std::set<std::string> names(options.topics.begin(), options.topics.end());
  for (const std::string& n : names) {
    if (!watchable().count(n)) {
      return usage_error("--topics: unknown topic '" + n +
                         "' (path, health, device, terrain, catalogue, thumbnail, acks)");
    }
  }
  Result<std::unique_ptr<Participant>> p = open(common);
  if (!p.ok()) return usage_error(p.status().message());
  std::vector<std::pair<Topic, Reader>> readers;
  for (const std::string& n : names) {
    const Topic topic = watchable().at(n);
    Result<Reader> r = Reader::create(**p, topic);
    if (!r.ok()) return failure(r.status().message());
    readers.emplace_back(topic, std::move(*r));
  }
  std::fprintf(stderr, "visvol-echo: watching %zu topic(s) on domain %u%s%s\n", readers.size(), common.domain,
               common.ns.empty() ? "" : ", namespace ", common.ns.c_str());

  const auto start = std::chrono::steady_clock::now();
  std::size_t printed = 0;
  while (!g_interrupted.load()) {
    (void)readers.front().second.wait(0.02);
    for (const auto& [topic, reader] : readers) printed += print_all(topic, reader, options.vertices, common.json);
    if (options.count > 0 && printed >= options.count) return kExitOk;
    const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (options.timeout_s > 0.0 && elapsed_s >= options.timeout_s) {
      if (options.count == 0) return kExitOk;
      return failure(std::to_string(printed) + " of " + std::to_string(options.count) + " message(s) within " +
                     seconds(options.timeout_s));
    }
  }
  return kExitOk;
}

// command --------------------------------------------------------------------

std::string default_source() {
  char host[64] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  std::string s = "visvol-echo@" + std::string(host) + ":" + std::to_string(::getpid());
  if (s.size() >= kSourceCapacity) s.resize(kSourceCapacity - 1);
  return s;
}

Result<Command> build_command(const CommandOptions& o) {
  Command c{};
  // a new number each run: the console keeps its last acknowledgements for
  // late joiners, and one of an earlier run under the same source and number
  // would pass for this one's
  c.sequence = o.sequence.value_or(static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count()));
  const std::string source = o.source_given ? o.source : default_source();
  VISVOL_RETURN_IF_ERROR(check_source(source).with_context("--source"));
  copy_text(c.source, source);
  const std::string& k = o.kind;
  if (k == "set-endpoints") {
    c.kind = CommandKind::set_endpoints;
    const std::vector<double>& v = o.numbers;
    c.endpoints = {{v.at(0), v.at(1), v.at(2)}, {v.at(3), v.at(4), v.at(5)}};
  } else if (k == "set-objective") {
    c.kind = CommandKind::set_objective;
    c.objective = o.word == "hide" ? Objective::hide : Objective::show;
  } else if (k == "set-weights") {
    c.kind = CommandKind::set_weights;
    c.weights = {o.numbers.at(0), o.numbers.at(1), o.numbers.at(2), o.numbers.at(3)};
  } else if (k == "set-stiffness") {
    c.kind = CommandKind::set_stiffness;
    c.stiffness = {o.numbers.at(0), o.numbers.at(1)};
  } else if (k == "set-model") {
    c.kind = CommandKind::set_model;
    c.model = o.word == "spring" ? RopeModel::spring_mass : RopeModel::articulated;
  } else if (k == "set-mode") {
    c.kind = CommandKind::set_mode;
    c.mode = o.word == "spool" ? InteractionMode::spool : InteractionMode::pull;
  } else if (k == "set-segments") {
    c.kind = CommandKind::set_segment_count;
    c.segment_count = o.segments;
  } else if (k == "set-constraints") {
    c.kind = CommandKind::set_constraints;
    const auto add = [&](const Constraint& constraint) -> Status {
      if (c.constraints.count >= kMaxConstraints) {
        return invalid_argument("more than " + std::to_string(kMaxConstraints) + " constraints");
      }
      c.constraints.items[c.constraints.count++] = constraint;
      return Status();
    };
    for (const std::string& p : o.hidden_from) {
      Result<WorldPoint> w = parse_point("--hidden-from", p);
      if (!w.ok()) return w.status();
      VISVOL_RETURN_IF_ERROR(add({ConstraintKind::hidden_from, *w, 0.0}));
    }
    for (const std::string& p : o.visible_to) {
      Result<WorldPoint> w = parse_point("--visible-to", p);
      if (!w.ok()) return w.status();
      VISVOL_RETURN_IF_ERROR(add({ConstraintKind::visible_to, *w, 0.0}));
    }
    for (const double m : o.clearances) VISVOL_RETURN_IF_ERROR(add({ConstraintKind::clearance, {}, m}));
    for (const double m : o.max_agls) VISVOL_RETURN_IF_ERROR(add({ConstraintKind::max_agl, {}, m}));
    for (const double m : o.max_altitudes) {
      VISVOL_RETURN_IF_ERROR(add({ConstraintKind::max_altitude, {}, m}));
    }
  } else if (k == "start") {
    c.kind = CommandKind::start;
  } else if (k == "stop") {
    c.kind = CommandKind::stop;
  } else if (k == "switch-terrain") {
    c.kind = CommandKind::switch_terrain;
    VISVOL_RETURN_IF_ERROR(check_pack_id("PACK_ID", o.word));
    copy_text(c.pack_id, o.word);
  } else {
    return invalid_argument("unknown command '" + k + "'");
  }
  return c;
}

int run_command(const Common& common, const CommandOptions& options) {
  Result<Command> command = build_command(options);
  if (!command.ok()) return usage_error(command.status().message());
  Result<std::unique_ptr<Participant>> p = open(common);
  if (!p.ok()) return usage_error(p.status().message());
  Result<Writer> writer = Writer::create(**p, Topic::command);
  if (!writer.ok()) return failure(writer.status().message());
  Result<Reader> acks = Reader::create(**p, Topic::command_ack);
  if (!acks.ok()) return failure(acks.status().message());

  // both ends seen before sending: a volatile command written earlier would
  // reach nobody; acks are transient-local, so one the console wrote before
  // its writer saw this reader still arrives
  const Status heard = writer->wait_for_readers(1, options.timeout_s);
  const Status hearing = heard.ok() ? acks->wait_for_writers(1, options.timeout_s) : heard;
  if (!hearing.ok()) {
    return failure("no command intake on domain " + std::to_string(common.domain) +
                   (common.ns.empty() ? "" : " namespace " + common.ns) + " within " + seconds(options.timeout_s));
  }
  CommandMessage msg;
  const dds_return_t rc = writer->write(&msg.fill(*command));
  if (rc < 0) return failure(dds_error("sending the command", rc).message());

  const std::string source(text_of(command->source));
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<long>(options.timeout_s * 1e3));
  int result = -1;
  while (result < 0 && !g_interrupted.load() && std::chrono::steady_clock::now() < deadline) {
    (void)acks->wait(0.05);
    (void)acks->take<visvol_msgs_msg_dds__CommandAck_>(
        [&](const visvol_msgs_msg_dds__CommandAck_& m, const dds_sample_info_t&) {
          if (result >= 0 || !m.source || source != m.source || m.sequence_number != command->sequence) {
            return;  // someone else's
          }
          std::printf("%s\n", (common.json ? echo::json_ack(m) : echo::format_ack(m)).c_str());
          std::fflush(stdout);
          const auto r = static_cast<AckResult>(m.result);
          if (r == AckResult::rejected || r == AckResult::failed) result = kExitFailure;
          if (r == AckResult::applied) result = kExitOk;
          if (r == AckResult::accepted && !options.wait_applied) result = kExitOk;
        });
  }
  if (result < 0) {
    return failure(std::string("no ") + (options.wait_applied ? "applied/failed " : "") + "acknowledgement within " +
                   seconds(options.timeout_s));
  }
  return result;
}

int run_topics() {
  std::printf("%-34s%-44s%s\n", "topic", "type", "QoS");
  for (int i = 0; i < kTopicCount; ++i) std::printf("%s\n", describe(static_cast<Topic>(i)).c_str());
  return kExitOk;
}

// command-line ---------------------------------------------------------------

void add_command_kinds(CLI::App& command, CommandOptions& o) {
  auto kind = [&](const char* name, const char* help) {
    CLI::App* sub = command.add_subcommand(name, help);
    sub->callback([&o, name] { o.kind = name; });
    return sub;
  };
  kind("set-endpoints", "both ends of the rope, world metres")
      ->add_option("X0 Y0 Z0 X1 Y1 Z1", o.numbers, "start and end point (m, pack CRS)")
      ->expected(6)
      ->required()
      ->check(kFinite);
  kind("set-objective", "hide (stealth) or show (surveillance)")
      ->add_option("OBJECTIVE", o.word, "hide or show")
      ->required()
      ->check(CLI::IsMember({"hide", "show"}));
  kind("set-weights", "force weights k1..k4 (magnitudes >= 0)")
      ->add_option("K1 K2 K3 K4", o.numbers, "visibility, terrain, user, constraint")
      ->expected(4)
      ->required()
      ->check(kFinite);
  kind("set-stiffness", "rope stiffness")
      ->add_option("STRETCH BEND", o.numbers, "stretch (N/m) and bending (N m/rad) stiffness")
      ->expected(2)
      ->required()
      ->check(kFinite);
  kind("set-model", "rope model")
      ->add_option("MODEL", o.word, "spring (spring-mass) or articulated")
      ->required()
      ->check(CLI::IsMember({"spring", "articulated"}));
  kind("set-mode", "interaction: pull (mode A) or spool (mode B: drag the rope out of the start)")
      ->add_option("MODE", o.word, "pull or spool")
      ->required()
      ->check(CLI::IsMember({"pull", "spool"}));
  kind("set-segments", "number of rope segments")
      ->add_option("N", o.segments, "segments (the console says how many it reserved)")
      ->required()
      ->check(CLI::Range(1u, 1000000u));
  CLI::App* constraints = kind(
      "set-constraints", "replace the observers (none given: clear them); clearance and ceilings change when given");
  constraints->add_option("--hidden-from", o.hidden_from,
                          "X,Y,Z: stay hidden from an observer standing there (m); repeatable");
  constraints->add_option("--visible-to", o.visible_to,
                          "X,Y,Z: stay visible to an observer standing there (m); repeatable");
  constraints->add_option("--clearance", o.clearances, "keep at least this height above the terrain (m)")
      ->check(kFinite);
  constraints->add_option("--max-agl", o.max_agls, "keep at most this height above the terrain (m)")->check(kFinite);
  constraints->add_option("--max-altitude", o.max_altitudes, "keep at most this height above the datum (m)")
      ->check(kFinite);
  kind("start", "start planning");
  kind("stop", "stop planning");
  kind("switch-terrain", "load another pack of the console")
      ->add_option("PACK_ID", o.word, "the pack's id")
      ->required();
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-echo")) return 0;
  static const char* const kMayBeEmpty[] = {"--namespace", nullptr};
  if (const int empty = visvol::first_empty_argument(argc, argv, kMayBeEmpty); empty > 0) {
    std::fprintf(stderr, "visvol-echo: %s (try --help)\n", visvol::empty_argument_problem(argv, empty).c_str());
    return 2;
  }
  Common common;
  WatchOptions watch;
  CommandOptions command;

  CLI::App app{
      "visvol-echo: prints the path updates and health a visvol console publishes over DDS, "
      "and sends it commands.\n"
      "Uses the built-in loopback configuration (127.0.0.1 only) unless --config names "
      "another; never CYCLONEDDS_URI."};
  app.set_version_flag("--version", visvol::version_line("visvol-echo"));  // listed in --help; handled first in main
  app.footer(
      "\nExamples:\n"
      "  visvol-echo path --count 1          the latest path (kept for late joiners), then exit\n"
      "  visvol-echo watch --topics path,health,acks\n"
      "  visvol-echo command set-objective hide\n"
      "  visvol-echo command set-endpoints 546600 4184900 150 552400 4184900 150\n"
      "  visvol-echo --domain 7 --config /etc/visvol/cyclone.xml --namespace console_a command stop\n"
      "\nExit status: 0 success (a command accepted), 1 failure while working (a command\n"
      "rejected or unanswered, too few messages within --timeout), 2 bad arguments.");
  app.fallthrough();
  app.require_subcommand(1);
  app.add_option("--domain", common.domain, "DDS domain id (0..232)")->check(CLI::Range(0u, kMaxDomainId));
  app.add_option("--config", common.config_file, "Cyclone DDS XML configuration file")->check(CLI::ExistingFile);
  app.add_option("--namespace", common.ns, "topic namespace of the console (ROS style)");
  app.add_flag("--json", common.json, "one JSON object per message and line (fields by their message names)");

  CLI::App* watch_app = app.add_subcommand("watch", "print messages as they arrive");
  watch_app
      ->add_option("--topics", watch.topics,
                   "path, health, device, terrain, catalogue, thumbnail, acks (default: path health)")
      ->delimiter(',');
  CLI::App* path_app = app.add_subcommand("path", "print path updates as they arrive");
  CLI::App* health_app = app.add_subcommand("health", "print health reports as they arrive");
  for (CLI::App* sub : {watch_app, path_app, health_app}) {
    sub->add_option("--count", watch.count, "exit after N messages (0: until interrupted)")
        ->check(CLI::NonNegativeNumber);
    sub->add_option("--timeout", watch.timeout_s, "give up after S seconds (exit 1 if --count was not reached)")
        ->check(kFinite)  // CLI::Range lets NaN through: it never timed out
        ->check(CLI::Range(0.0, 86400.0));
    sub->add_flag("--vertices", watch.vertices, "print every vertex of a path");
  }
  path_app->callback([&] { watch.topics = {"path"}; });
  health_app->callback([&] { watch.topics = {"health"}; });

  CLI::App* command_app = app.add_subcommand("command", "send one command and print its acknowledgement");
  command_app->require_subcommand(1);
  CLI::Option* source_option = command_app->add_option(
      "--source", command.source, "sender name in the acknowledgement (default visvol-echo@HOST:PID)");
  command_app
      ->add_option("--sequence", command.sequence,
                   "the command's number (default: milliseconds since 1970, new each run); "
                   "the console keeps its last 1024 answers, so a number this --source used "
                   "before may be answered by the old acknowledgement")
      ->check(CLI::NonNegativeNumber);
  command_app->add_option("--timeout", command.timeout_s, "seconds to wait for the console and its answer (default 5)")
      ->check(kFinite)
      ->check(CLI::Range(0.1, 3600.0));
  command_app->add_flag("--wait-applied", command.wait_applied,
                        "wait until the planner reports the command applied or failed");
  add_command_kinds(*command_app, command);

  CLI::App* topics_app = app.add_subcommand("topics", "print the topics, types and QoS");

  visvol::decimal_numbers(app);  // "010" is ten, not octal eight
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::printf("%s", app.help().c_str());
    return kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::printf("%s", app.help("", CLI::AppFormatMode::All).c_str());
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help of a subcommand
      const CLI::App* sub = &app;
      while (!sub->get_subcommands().empty()) sub = sub->get_subcommands().front();
      std::printf("%s", sub->help().c_str());
      return kExitOk;
    }
    return usage_error(e.what());
  }
  command.source_given = source_option->count() > 0;
  {
    const Status ns = validate_namespace(common.ns);
    if (!ns.ok()) return usage_error("--namespace: " + ns.message());
  }

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  if (topics_app->parsed()) return run_topics();
  if (command_app->parsed()) return run_command(common, command);
  return run_watch(common, watch);
}
