// visvol on crafted packs (checksums consistent, contents hostile): every
// command that opens a pack refuses it with exit status 2, as for a corrupt
// tile, naming the file and the problem; never a signal.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

#include "../storage/crafted_pack.hpp"
#include "cli_runner.hpp"

namespace {

using visvol::storage::testing::CraftedPack;
using visvol::test::Outcome;
using visvol::test::visvol;

class CraftedCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // the project's own writer, on a 40 x 40 window of the bundled DEM (it has a CRS, which plan needs)
    valid_ = new std::string(::testing::TempDir() + "/crafted_cli_" + std::to_string(getpid()) + ".vvp");
    const Outcome r = visvol("build " + visvol::test::kDem + " " + visvol::test::kSmallPackOptions + " -o " + *valid_);
    ASSERT_EQ(r.status, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::remove(valid_->c_str());
    delete valid_;
  }
  static std::string* valid_;
};
std::string* CraftedCli::valid_ = nullptr;

// The commands a user runs on a pack: a point and a plan in the middle of it
// (the window is 40 x 40 posts of 30 m, post (0, 0) at (549990, 4182750)).
struct Command {
  const char* name;
  std::string args;  // after the pack path
  std::string input;
};
const std::vector<Command>& commands() {
  static const std::vector<Command> c = {
      {"info", "", ""},
      {"info", "--json", ""},
      {"verify", "", ""},
      {"sample", "--layer tff", "550590 4182150 300\n"},
      {"sample", "--layer gradient", "550590 4182150 300\n"},
      {"plan",
       "--objective hide --from 550300 4182150 400 --to 550850 4182150 400 --segments 16 -o " + ::testing::TempDir() +
           "/crafted_cli_plan",
       ""},
  };
  return c;
}

TEST_F(CraftedCli, TheUncraftedPackPassesEveryCommand) {
  const std::string copy = ::testing::TempDir() + "/crafted_cli_copy_" + std::to_string(getpid()) + ".vvp";
  CraftedPack(*valid_).write(copy);
  for (const Command& c : commands()) {
    const Outcome r = visvol(std::string(c.name) + " " + copy + " " + c.args, c.input);
    EXPECT_EQ(r.status, 0) << c.name << " " << c.args << ": " << r.err;
  }
  std::remove(copy.c_str());
}

// A file name is bytes, not always UTF-8 (a pack copied from an old file
// system): every command takes it, and the JSON that names it stays JSON
// (the bad byte written as U+FFFD) instead of aborting.
TEST_F(CraftedCli, APackNameThatIsNotUtf8IsTakenAndItsJsonStaysValid) {
  const std::string copy = ::testing::TempDir() + "/crafted_cli_latin1_\xff_" + std::to_string(getpid()) + ".vvp";
  CraftedPack(*valid_).write(copy);
  for (const Command& c : commands()) {
    const std::string name = c.name;
    const bool json = name == "info" || name == "plan";
    const std::string args = c.args.find("--json") == std::string::npos && json ? c.args + " --json" : c.args;
    const Outcome r = visvol(name + " '" + copy + "' " + args, c.input);
    EXPECT_EQ(r.status, 0) << name << " " << args << ": " << r.err;
    if (json) {
      const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
      EXPECT_FALSE(j.is_discarded()) << name << " " << args << " wrote no JSON: " << r.out;
    }
  }
  std::remove(copy.c_str());
}

TEST_F(CraftedCli, EveryCommandRefusesAHostilePackWithStatus2) {
  struct Case {
    const char* what;
    std::function<void(CraftedPack&)> edit;
    const char* expect;
  };
  auto metadata = [](const char* key, const nlohmann::json& value) {
    return [key, value](CraftedPack& p) {
      nlohmann::json j = nlohmann::json::parse(p.metadata());
      j[key] = value;
      p.set_metadata(j.dump());
    };
  };
  const std::vector<Case> cases = {
      {"NaN height", [](CraftedPack& p) { p.set_height(0, 20, 20, NAN); }, "post (20, 20) has height nan"},
      {"denormal dz", [](CraftedPack& p) { p.level(0).dz_m = p.level(1).dz_m = 4.9406564584124654e-324; },
       "voxel level spacing dz 4.9406564584124654e-324 m"},
      {"NaN origin", [](CraftedPack& p) { p.level(0).origin_y = NAN; }, "level 0: origin (549990, nan)"},
      {"tool {}", metadata("tool", nlohmann::json::object()), "metadata tool is {}, not a string"},
      {"build []", metadata("build", nlohmann::json::array()), "metadata build is [], not an object"},
  };
  const std::string bad = ::testing::TempDir() + "/crafted_cli_bad_" + std::to_string(getpid()) + ".vvp";
  for (const Case& k : cases) {
    CraftedPack pack(*valid_);
    k.edit(pack);
    pack.write(bad);
    for (const Command& c : commands()) {
      const Outcome r = visvol(std::string(c.name) + " " + bad + " " + c.args, c.input);
      EXPECT_EQ(r.status, 2) << k.what << ", " << c.name << " " << c.args << ": " << r.err;
      EXPECT_NE(r.err.find(bad + ": "), std::string::npos) << k.what << ", " << c.name << ": " << r.err;
      EXPECT_NE(r.err.find(k.expect), std::string::npos) << k.what << ", " << c.name << ": " << r.err;
    }
  }
  std::remove(bad.c_str());
}

}  // namespace
