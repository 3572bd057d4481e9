// Runs the visvol binary as users do (shell words, stdin text) and collects
// its exit status and output. Shared by the tests of tools/visvol.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace visvol::test {

struct Outcome {
  int status = -1;
  std::string out, err;
};

inline std::string slurp(const std::string& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs a shell command line with `input` on stdin; its status and output.
inline Outcome run_command(const std::string& command, const std::string& input = "") {
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(getpid());
  const std::string in = dir + "/cli_in_" + tag, out = dir + "/cli_out_" + tag, err = dir + "/cli_err_" + tag;
  std::ofstream(in) << input;
  const int rc = std::system((command + " <" + in + " >" + out + " 2>" + err).c_str());
  Outcome r;
  r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  for (const std::string& f : {in, out, err}) std::remove(f.c_str());
  return r;
}

inline Outcome visvol(const std::string& args, const std::string& input = "") {
  return run_command(std::string(VISVOL_BIN) + " " + args, input);
}

// The bundled SF North DEM and a hilly 40 x 40 window of it (pixel edges on
// its 30 m grid), small enough for a pack in a second.
inline const std::string kDem = std::string(VISVOL_TEST_DATA) + "/sf_north_utm10_30m.tif";
inline const std::string kCrop = "--crop 549975 4181565 551175 4182765";
inline const std::string kSmallPackOptions = kCrop + " --levels 16 --range 8 --lod 2 --tff-offset 60 --tff-levels 6";

}  // namespace visvol::test
