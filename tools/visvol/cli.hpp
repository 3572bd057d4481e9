// Shared pieces of the visvol command: progress display and failure exits.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "base/status.hpp"

namespace visvol::cli {

// Exit statuses: 0 success, 1 a failure while working, 2 bad arguments or input.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// The exit status for a status: 0 ok, 2 bad arguments or input, 1 otherwise.
int exit_code(const Status& status);

// Prints "visvol <command>: <message>" on stderr and returns exit_code(status).
int fail(const std::string& command, const Status& status);

// Refuses an output that is already one of the command's inputs (the same
// file: device and inode, so "./x", links and hard links too), which the
// command would overwrite while it reads it (export -o its own pack, build
// -o its DEM). `inputs`: (what the input is called, its path); empty paths
// and files that do not exist are skipped. Errc::invalid_argument naming both.
Status output_is_no_input(const std::string& output, const std::string& output_name,
                          const std::vector<std::pair<std::string, std::string>>& inputs);

// Writes a small text file whole or not at all (temporary file, fsync, rename).
Status write_text_file(const std::string& path, const std::string& text);

// Progress on stderr: a redrawn bar on a terminal, a plain line every 10%
// otherwise (logs stay readable). Call update() from one thread.
class Progress {
 public:
  explicit Progress(std::string label);
  ~Progress();
  void update(double fraction);
  void finish();

 private:
  std::string label_;
  bool tty_;
  int last_decile_ = -1;
  int last_width_ = -1;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace visvol::cli
