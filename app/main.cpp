// visvol-console: the planning console. Maps a field pack within a memory
// budget, runs the rope and the haptic servo at 1 kHz against the haptic
// device (simulated by default), publishes the path over DDS and takes
// commands, until the time is up or Ctrl-C. A switch-terrain command to
// one of its --terrain packs ends the session and starts one on that pack
// (or, when that one cannot start, goes back to the pack it left).
//
// Exit status: 0 success, 1 a failure while running, 2 bad options or input.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <optional>

#include "app/console.hpp"
#include "app/log.hpp"
#include "base/arguments.hpp"
#include "base/version.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

// One session per pack: a switch-terrain command ends a session and the next
// one starts on the other pack, everything made anew. Returns the exit status.
// CLI11 and the option checks name the option (or the key), not where its
// value came from: " (options from the command line and --config FILE)"
// when a file was read.
std::string config_note(const CLI::App& cli) {
  const CLI::Option* config = cli.get_config_ptr();
  // the text as given (as<>() would run the option's checks again, and throw)
  return config != nullptr && !config->results().empty()
             ? " (options from the command line and --config " + config->results().front() + ")"
             : "";
}

int run_sessions(const visvol::app::ConsoleOptions& options) {
  using namespace visvol;
  std::optional<app::ConsoleOptions> session = options;
  while (session) {
    auto console = app::Console::start(*session);
    if (!console.ok()) {
      app::log_printf(app::LogLevel::error, "visvol-console: %s\n", console.status().message().c_str());
      if (!session->switched_from.empty()) {
        // a switch that cannot start ends nothing: back to the pack it left
        session = app::session_after_failed_switch(*session, console.status().message());
        app::log_printf(app::LogLevel::warning, "visvol-console: switch-terrain failed; back on %s\n",
                        session->pack.c_str());
        continue;
      }
      const Errc c = console.status().code();
      const bool bad_input = c == Errc::invalid_argument || c == Errc::resource || c == Errc::corrupt;
      return bad_input && session->session == 1 ? 2 : 1;
    }
    const Status s = (*console)->run(g_stop);
    if (!s.ok()) {
      app::log_printf(app::LogLevel::error, "visvol-console: %s\n", s.message().c_str());
      return 1;
    }
    session = g_stop.load() ? std::nullopt : (*console)->next_session();
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol-console")) return 0;
  static const char* const kMayBeEmpty[] = {"--namespace", nullptr};
  if (const int empty = visvol::first_empty_argument(argc, argv, kMayBeEmpty); empty > 0) {
    std::fprintf(stderr, "visvol-console: %s (try --help)\n", visvol::empty_argument_problem(argv, empty).c_str());
    return 2;
  }
  using namespace visvol;
  CLI::App cli{
      "visvol-console: interactive path optimisation in a visibility field (Srikanth et al.), with the rope and "
      "the haptic servo at 1 kHz and the path on DDS.\n"
      "Example: visvol-console --pack out/sf_north.vvp --seconds 20 --out out/console"};
  cli.set_version_flag("--version", visvol::version_line("visvol-console"));  // listed in --help; handled first in main
  app::ConsoleOptions options;
  app::add_console_options(cli, options);
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      std::printf("%s", cli.help().c_str());
      return 0;
    }
    app::log_printf(app::LogLevel::error, "visvol-console: %s%s (try --help)\n",
                    app::config_error_text(e.what()).c_str(), config_note(cli).c_str());
    return 2;
  }
  // checked here too (each session checks again), so that a bad value names
  // the configuration file it may have come from
  if (const visvol::Status v = app::validate(options); !v.ok()) {
    app::log_printf(app::LogLevel::error, "visvol-console: %s%s\n", v.message().c_str(), config_note(cli).c_str());
    return 2;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  // Nothing should throw past a session (errors are Status values); if
  // something does, say so and exit 1 rather than abort without a word.
  try {
    return run_sessions(options);
  } catch (const std::exception& e) {
    app::log_printf(app::LogLevel::error, "visvol-console: internal error: %s\n", e.what());
  } catch (...) {
    app::log_printf(app::LogLevel::error, "visvol-console: internal error (unknown exception)\n");
  }
  return 1;
}
