// Absurd option values through the visvol command (red team, issue 14): each
// is refused with exit 2 and a message naming the option and its range,
// before any long work; none aborts.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"

namespace {

using visvol::test::kCrop;
using visvol::test::kDem;
using visvol::test::kSmallPackOptions;
using visvol::test::Outcome;
using visvol::test::visvol;

std::string temp(const std::string& stem) {
  return ::testing::TempDir() + "/ranges_" + stem + "_" + std::to_string(getpid());
}

void expect_refused(const std::string& args, const std::vector<std::string>& named) {
  const Outcome r = visvol(args);
  EXPECT_EQ(r.status, 2) << args << ": " << r.err;
  for (const std::string& n : named) EXPECT_NE(r.err.find(n), std::string::npos) << n << ": " << r.err;
}

TEST(OptionRanges, ViewshedMaxDistanceOutOfRangeIsRefusedNotAborted) {
  const std::string out = temp("vs") + ".tif";
  expect_refused(
      "viewshed " + kDem + " --fill-nodata " + kCrop + " --observer 550500 4182000 --max-distance 1e308 -o " + out,
      {"max distance: 1e+308 m is outside 0..1e+08 m"});
  EXPECT_NE(access(out.c_str(), F_OK), 0);
}

TEST(OptionRanges, BuildMaxMemoryTooLargeIsRefusedByItsRange) {
  const std::string out = temp("mem") + ".vvp";
  expect_refused("build " + kDem + " " + kSmallPackOptions + " --max-memory 1e308 -o " + out,
                 {"memory limit: 1e+308 MiB is outside 0..16777216 MiB"});
  EXPECT_NE(access(out.c_str(), F_OK), 0);
}

TEST(OptionRanges, InfoRefusesAnOversizedResampleBeforeWarping) {
  const std::string hgt = std::string(VISVOL_SHARED_DATA) + "/dem/N50E008.hgt";
  if (access(hgt.c_str(), R_OK) != 0) GTEST_SKIP() << hgt << " not found";
  // It warped for 60 s and 3.6 GB before refusing a size known from the header.
  const auto t0 = std::chrono::steady_clock::now();
  expect_refused("info " + hgt + " --spacing 3", {hgt, "would be", "posts at 3 m spacing", "--spacing"});
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
}

class PlanRanges : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pack_ = new std::string(temp("pack") + ".vvp");
    const Outcome r = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + *pack_);
    ASSERT_EQ(r.status, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::remove(pack_->c_str());
    delete pack_;
  }
  // A plan on the small pack: its planning bounds are x 550230..550920, y 4181820..4182510.
  static std::string plan(const std::string& args) {
    return "plan " + *pack_ + " --from 550300 4181900 200 --to 550800 4182400 200 --objective hide " + args + " -o " +
           temp("plan");
  }
  static std::string* pack_;
};
std::string* PlanRanges::pack_ = nullptr;

TEST_F(PlanRanges, SlackOutsideItsRangeIsRefused) {
  expect_refused(plan("--init straight --slack -1e300"), {"--slack", "not in range 0.000000 to 10.000000"});
  expect_refused(plan("--init straight --slack 11"), {"--slack"});
}

TEST_F(PlanRanges, InitPointsOffThePackOrUndergroundAreRefusedByIndex) {
  const std::string far = temp("init_far") + ".txt";
  std::ofstream(far) << "550400 4182000\n550500 4182100\n10550600 4182300\n";
  expect_refused(plan("--init " + far),
                 {"--init " + far, "point 3 (10550600.0, 4182300.0)", "outside the pack's planning bounds"});
  // With heights: a mission 87 m underground was written with exit 0.
  const std::string deep = temp("init_deep") + ".txt";
  std::ofstream(deep) << "550400 4182000 400\n550600 4182300 -1e7\n";
  expect_refused(plan("--init " + deep), {"point 2", "m below the terrain"});
  const std::string high = temp("init_high") + ".txt";
  std::ofstream(high) << "550400 4182000 1e7\n550600 4182300 400\n";
  expect_refused(plan("--init " + high), {"point 1", "over the field's top"});
  for (const std::string& f : {far, deep, high}) std::remove(f.c_str());
  EXPECT_NE(access((temp("plan") + ".plan").c_str(), F_OK), 0);
}

TEST_F(PlanRanges, SegmentsAndTheirWorkAreBoundedBeforePlanning) {
  const auto t0 = std::chrono::steady_clock::now();
  expect_refused(plan("--init straight --segments 100000 --max-seconds 1"), {"100000 segments is outside 2..4096"});
  expect_refused(plan("--init straight --segments 1000 --max-seconds 100"),
                 {"vertex steps a level", "--segments", "--max-seconds"});
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
}

}  // namespace
