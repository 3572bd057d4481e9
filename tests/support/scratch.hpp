// Paths a test binary names through scratch_path() under
// ::testing::TempDir(), removed with all that they hold when the binary
// exits, passed or failed (the console's and the catalogue's tests left some
// 30 folders there a run, 4 GiB after a hundred runs). Header only; any test
// includes it.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

namespace visvol::test {

namespace scratch_detail {

class Registry {
 public:
  void add(const std::string& path) {
    const std::lock_guard<std::mutex> lock(mutex_);
    paths_.push_back(path);
  }
  ~Registry() {
    // only the process that made them: a forked child that exits normally
    // must not take its parent's files
    if (getpid() != owner_) return;
    for (const std::string& p : paths_) {
      std::error_code ec;  // gone already, or never made: nothing to do
      std::filesystem::remove_all(p, ec);
    }
  }

 private:
  std::mutex mutex_;
  std::vector<std::string> paths_;
  pid_t owner_ = getpid();
};

inline Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace scratch_detail

// TempDir()/<name>_<pid> (a file or a folder, as the test makes it; not
// created here), removed when the binary exits.
inline std::string scratch_path(const std::string& name) {
  const std::string path = ::testing::TempDir() + "/" + name + "_" + std::to_string(getpid());
  scratch_detail::registry().add(path);
  return path;
}

}  // namespace visvol::test
