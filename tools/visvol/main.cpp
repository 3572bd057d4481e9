// visvol: visibility volumes for flight-path planning.
//
//   visvol build DEM -o PACK [options]  field pack: F_p, levels of detail, terrain force field
//   visvol info PACK|DEM [--json]
//   visvol verify PACK
//   visvol sample PACK [--layer L] [--lod K] < points
//   visvol viewshed DEM --observer X Y -o OUT.tif
//   visvol export PACK --layer L --format mhd|vti -o FILE
//   visvol plan PACK --from X Y Z --to X Y Z --objective hide|show -o OUT
//   visvol check PACK PATH [--hidden-from X Y Z] [--visible-to X Y Z] [--vehicle V] [--json]
//   visvol render PACK [--path FILE] [--size WxH] [--view V] [--transfer FILE] -o OUT.png
//
// Exit status: 0 success, 1 failure while working, 2 bad arguments or input.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <map>
#include <new>
#include <string>

#include "base/arguments.hpp"
#include "base/cli_numbers.hpp"
#include "base/terminal_text.hpp"
#include "base/version.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "io/atomic_file.hpp"

namespace {

// Runs a command; an exception that escapes it (a library's, or memory
// running out) ends it with a message and exit 1, never an abort.
int run_guarded(const std::string& command, const visvol::cli::Runner& runner) {
  try {
    const int status = runner();
    // what a command printed is its result (sample's values, check's
    // verdict): lost to a full disk or /dev/full, it must not exit 0
    errno = 0;
    const bool flushed = std::fflush(stdout) == 0;
    const int flush_errno = errno;
    if (!flushed || std::ferror(stdout) != 0) {
      std::fprintf(stderr, "visvol %s: writing the standard output failed (%s): its results are incomplete\n",
                   command.c_str(), !flushed && flush_errno != 0 ? std::strerror(flush_errno) : "an earlier write");
      return std::max(status, static_cast<int>(visvol::cli::kExitFailure));
    }
    return status;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "visvol %s: out of memory\n", command.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "visvol %s: internal error: %s\n", command.c_str(), e.what());
  } catch (...) {
    std::fprintf(stderr, "visvol %s: internal error (unknown exception)\n", command.c_str());
  }
  return visvol::cli::kExitFailure;
}

}  // namespace

int main(int argc, char** argv) {
  if (visvol::print_version_if_asked(argc, argv, "visvol")) return 0;
  static const char* const kMayBeEmpty[] = {"--namespace", nullptr};  // plan --publish: empty by default
  if (const int empty = visvol::first_empty_argument(argc, argv, kMayBeEmpty); empty > 0) {
    std::fprintf(stderr, "visvol: %s (try --help)\n", visvol::empty_argument_problem(argv, empty).c_str());
    return visvol::cli::kExitUsage;
  }
  using namespace visvol::cli;
  // Ctrl-C or a kill during a build leaves no PACK.tmp.<host>.<pid> behind
  visvol::install_output_cleanup_on_signals();
  // packs are read through memory maps: one cut short under a command faults
  // its next read (a "Bus error" before)
  visvol::install_mapped_read_fault_handler(
      "visvol: a file read through memory (a pack, or a DEM) was cut short or rewritten while this command read it "
      "(copied over in place?); write a new one beside it and rename it over the old one\n");
  CLI::App app{
      "visvol: visibility volumes above terrain (the field F_p of Srikanth et al., "
      "\"Visibility Volumes for Interactive Path Optimization\")"};
  app.set_version_flag("--version", visvol::version_line("visvol"));  // listed in --help; handled first in main
  app.require_subcommand(1);
  std::map<std::string, Runner> runners;
  runners["build"] = add_build_command(app);
  runners["info"] = add_info_command(app);
  runners["verify"] = add_verify_command(app);
  runners["sample"] = add_sample_command(app);
  runners["viewshed"] = add_viewshed_command(app);
  runners["export"] = add_export_command(app);
  runners["plan"] = add_plan_command(app);
  runners["check"] = add_check_command(app);
  runners["render"] = add_render_command(app);
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
    // Subcommand help arrives as CallForHelp raised inside the subcommand.
    if (e.get_exit_code() == 0) {
      for (CLI::App* sub : app.get_subcommands()) std::printf("%s", sub->help().c_str());
      if (app.get_subcommands().empty()) std::printf("%s", app.help().c_str());
      return kExitOk;
    }
    // CLI11 reads an unknown first word as a missing subcommand: name it
    if (argc > 1 && argv[1][0] != '-' && runners.count(argv[1]) == 0) {
      std::string known;
      for (const auto& r : runners) known += (known.empty() ? "" : ", ") + r.first;
      std::fprintf(stderr, "visvol: unknown command '%s' (commands: %s; try --help)\n",
                   visvol::terminal_safe(argv[1], 80).c_str(), known.c_str());
      return kExitUsage;
    }
    std::fprintf(stderr, "visvol: %s (try --help)\n", visvol::terminal_safe(e.what()).c_str());
    return kExitUsage;
  } catch (const std::exception& e) {  // an option's own conversion or check
    std::fprintf(stderr, "visvol: %s (try --help)\n", visvol::terminal_safe(e.what()).c_str());
    return kExitUsage;
  }
  for (CLI::App* sub : app.get_subcommands()) return run_guarded(sub->get_name(), runners.at(sub->get_name()));
  return kExitUsage;
}
