// What the console's process tests share (console_test, console_dds_test,
// console_terrain_test): the console run as an operator runs it, a pack
// built once per test binary, an operator script, path.csv's rows.
#pragma once

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "../fields/terrains.hpp"
#include "../storage/crafted_pack.hpp"
#include "../tools/cli_runner.hpp"
#include "console_packs.hpp"
#include "drivers/dds/command_codec.hpp"
#include "drivers/dds/message_codec.hpp"
#include "drivers/dds/participant.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "tests/support/scratch.hpp"

namespace visvol::app::console_process_test {

using visvol::test::Outcome;
using visvol::test::slurp;

// The data rows of a session's path.csv: after its '#' lines and its header.
inline std::vector<std::string> path_rows(const std::string& file) {
  std::istringstream csv(slurp(file));
  std::vector<std::string> rows;
  bool header = false;
  for (std::string row; std::getline(csv, row);) {
    if (row.empty() || row[0] == '#') continue;
    if (!header) {
      header = true;  // x_m,y_m,z_m,fp,clearance_m
      continue;
    }
    rows.push_back(row);
  }
  return rows;
}

inline Outcome console(const std::string& args, const std::string& prefix = "") {
  // the runner's binary is visvol; point it at the console instead
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(getpid());
  const std::string out = dir + "/console_out_" + tag, err = dir + "/console_err_" + tag;
  const std::string cmd = prefix + VISVOL_CONSOLE + " " + args + " </dev/null >" + out + " 2>" + err;
  const int rc = std::system(cmd.c_str());
  Outcome r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

// The console under a 30 s limit: a hang exits 124 (or 137) instead of stalling the suite.
inline Outcome console_limited(const std::string& args) { return console(args, "timeout -k 5 30 "); }

using visvol::app::testing::small_pack_params;

class Console : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pack_ = new std::string(::testing::TempDir() + "/console_" + std::to_string(getpid()) + ".vvp");
    ASSERT_TRUE(
        visvol::storage::build_pack(visvol::fields::testing::fractal(97, 5), small_pack_params(), "", *pack_).ok());
    // grab at 0.5 s, pull, let go at 2 s
    script_ = new std::string(::testing::TempDir() + "/console_script_" + std::to_string(getpid()) + ".txt");
    // pull mode (A), then spool mode (B): the mode button (the handle then
    // holds the lead's free end) and a drag past the far end in 60 mm strokes
    // (the default ends run west to east across the workspace's x, +-100 mm)
    std::ofstream(*script_) << "0.3 move 0 0 0 0.1\n0.5 pull 20 0 -20 1.0\n2.0 release\n"
                               "2.2 mode on\n2.3 mode off\n2.4 drag 213 0 0 2.0 60\n"
                               "4.7 release\n";
  }
  static void TearDownTestSuite() {
    std::remove(pack_->c_str());
    std::remove(script_->c_str());
    delete pack_;
    delete script_;
  }
  // removed with what the console wrote there when the binary exits
  static std::string out_dir(const std::string& name) { return visvol::test::scratch_path("console_" + name); }
  // Post (i, j) of the pack's finest level, `up_m` above the terrain: "X Y Z".
  static std::vector<double> post(int i, int j, double up_m) {
    auto pack = visvol::storage::Pack::open(*pack_);
    EXPECT_TRUE(pack.ok());
    auto level = visvol::storage::PackLevel::open(*pack, 0);
    EXPECT_TRUE(level.ok());
    const visvol::fields::VolumeGeometry g = level->geometry();
    return {g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, level->post(i, j) + up_m};
  }
  static std::string xyz(const std::vector<double>& p) {
    return std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]);
  }

  inline static std::string* pack_ = nullptr;
  inline static std::string* script_ = nullptr;
};

}  // namespace visvol::app::console_process_test
