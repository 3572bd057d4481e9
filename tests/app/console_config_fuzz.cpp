// libFuzzer target: the console's configuration file (--config FILE, INI or
// TOML, long option names as keys). Any bytes must be refused with a message
// (by CLI11 or by validate()) or give options that hold what the console's
// start-up relies on: never a crash, a hang or an uncaught exception.
#include <sys/mman.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "app/console_options.hpp"

namespace {

void expect(bool holds) {
  if (!holds) std::abort();  // libFuzzer keeps the input
}

bool finite_point(const std::vector<double>& p) {
  for (double v : p) {
    if (!std::isfinite(v)) return false;
  }
  return p.empty() || p.size() == 3;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const int fd = memfd_create("console_config", MFD_CLOEXEC);
  if (fd < 0) return 0;
  if (write(fd, data, size) != static_cast<ssize_t>(size)) {
    close(fd);
    return 0;
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  CLI::App cli{"visvol-console"};
  visvol::app::ConsoleOptions o;
  visvol::app::add_console_options(cli, o);
  // --pack must name a file that exists: the command line gives one (it
  // overrides the file), so that the rest of the file reaches validate()
  const char* argv[] = {"visvol-console", "--pack", "/proc/self/exe", "--config", path.c_str()};
  try {
    cli.parse(5, argv);
  } catch (const CLI::ParseError&) {
    close(fd);  // refused by CLI11, with its message (or --help asked for)
    return 0;
  }
  const visvol::Status valid = visvol::app::validate(o);
  if (!valid.ok()) {
    expect(!valid.message().empty());
  } else {
    // what Console::start takes for granted once validate() passed
    expect(o.segments >= 2 && o.segments <= o.max_segments && o.max_segments <= 4096);
    expect(std::isfinite(o.seconds) && o.seconds >= 0);
    expect(std::isfinite(o.k1) && std::isfinite(o.k2) && std::isfinite(o.k3));
    expect(o.period_us >= 100 && o.period_us <= 100000);
    expect(finite_point(o.from) && finite_point(o.to));
    expect(visvol::app::parse_thumbnail_size(o.thumbnail_size).ok());
  }
  close(fd);
  return 0;
}
