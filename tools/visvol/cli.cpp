#include "cli.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "base/terminal_text.hpp"
#include "io/atomic_file.hpp"

namespace visvol::cli {

int exit_code(const Status& status) {
  if (status.ok()) return kExitOk;
  const bool input = status.code() == Errc::invalid_argument || status.code() == Errc::io ||
                     status.code() == Errc::corrupt || status.code() == Errc::unsupported;
  return input ? kExitUsage : kExitFailure;
}

int fail(const std::string& command, const Status& status) {
  std::fprintf(stderr, "visvol %s: %s\n", command.c_str(), terminal_safe(status.message()).c_str());
  return exit_code(status);
}

Status output_is_no_input(const std::string& output, const std::string& output_name,
                          const std::vector<std::pair<std::string, std::string>>& inputs) {
  struct stat out {};
  if (output.empty() || ::stat(output.c_str(), &out) != 0) return Status::ok_status();
  for (const auto& [name, path] : inputs) {
    struct stat in {};
    if (path.empty() || ::stat(path.c_str(), &in) != 0) continue;
    if (in.st_dev == out.st_dev && in.st_ino == out.st_ino) {
      return invalid_argument(output_name + " " + output + " is the " + name + " " + path +
                              " it reads: the command would overwrite its own input; name another output");
    }
  }
  return Status::ok_status();
}

Status write_text_file(const std::string& path, const std::string& text) { return write_file_atomically(path, text); }

Progress::Progress(std::string label)
    : label_(std::move(label)), tty_(::isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
  if (tty_ && last_width_ >= 0 && !finished_) std::fputc('\n', stderr);
}

void Progress::update(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (tty_) {
    constexpr int kBar = 30;
    const int width = static_cast<int>(fraction * kBar + 0.5);
    if (width == last_width_ && fraction < 1.0) return;
    last_width_ = width;
    std::fprintf(stderr, "\r%s [%s%s] %3.0f%% %6.1f s", label_.c_str(),
                 std::string(static_cast<std::size_t>(width), '#').c_str(),
                 std::string(static_cast<std::size_t>(kBar - width), ' ').c_str(), 100.0 * fraction, elapsed);
    std::fflush(stderr);
    return;
  }
  const int decile = static_cast<int>(fraction * 10.0);
  if (decile == last_decile_) return;
  last_decile_ = decile;
  std::fprintf(stderr, "%s: %3d%% (%.1f s)\n", label_.c_str(), decile * 10, elapsed);
}

void Progress::finish() {
  update(1.0);
  if (tty_ && !finished_) std::fputc('\n', stderr);
  finished_ = true;
}

}  // namespace visvol::cli
