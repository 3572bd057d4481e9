// Hostile DEMs through the commands that import them (build, info,
// viewshed): each family of bad input exits 2 naming the file and the
// problem, and writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "../fields/gdal/hostile_rasters.hpp"
#include "cli_runner.hpp"

namespace {

using visvol::fields::testing::asc_text;
using visvol::fields::testing::TiffSpec;
using visvol::fields::testing::write_hostile_tiff;
using visvol::fields::testing::write_text;
using visvol::test::Outcome;
using visvol::test::visvol;

// `command DEM ARGS` is refused with exit 2, one line naming the file and
// every one of `named`, and no output file.
void expect_refused(const std::string& command, const std::string& dem, const std::string& args,
                    const std::vector<std::string>& named) {
  const std::string out = ::testing::TempDir() + "/import_cli_" + std::to_string(getpid()) + ".out";
  const Outcome r = visvol(command + " " + dem + " " + args + " -o " + out);
  EXPECT_EQ(r.status, 2) << command << " " << args << ": " << r.err;
  EXPECT_NE(r.err.find(dem), std::string::npos) << r.err;
  for (const std::string& n : named) EXPECT_NE(r.err.find(n), std::string::npos) << n << ": " << r.err;
  EXPECT_NE(access(out.c_str(), F_OK), 0);
  std::remove(out.c_str());
}

const std::string kAssume = "--assume-srs EPSG:32633";

TEST(ImportCli, ANonNumericCellIsRefusedNotReadAsZero) {
  const std::string dem = write_text("cli_bad_cell", ".asc", asc_text(40, "30", "500000", "abc"));
  expect_refused("build", dem, kAssume, {"cell (5, 3)", "'abc', not a number"});
  std::remove(dem.c_str());
}

TEST(ImportCli, AnUnknownVerticalUnitIsRefusedNamingIt) {
  TiffSpec spec;
  spec.n = 40;
  spec.unit = "furlong";
  const std::string dem = write_hostile_tiff("cli_furlong", spec);
  expect_refused("build", dem, "", {"heights are in 'furlong'", "does not know"});
  const Outcome info = visvol("info " + dem);
  EXPECT_EQ(info.status, 2) << info.err;
  std::remove(dem.c_str());
}

TEST(ImportCli, AFlippedGridIsRefusedNotRotated) {
  const std::string dem = write_text("cli_flipped", ".asc", asc_text(40, "-30"));
  expect_refused("build", dem, kAssume, {"pixel size -30 x 30", "not north-up"});
  expect_refused("viewshed", dem, kAssume + " --observer 500600 4000600", {"not north-up"});
  std::remove(dem.c_str());
}

TEST(ImportCli, CellSizesOutsideTheRangeAreRefusedStatingIt) {
  const std::pair<std::string, std::string> cells[] = {{"1e30", "1e+30"}, {"1e-9", "1e-09"}};
  for (const auto& [cell, shown] : cells) {
    const std::string dem = write_text("cli_cell_range", ".asc", asc_text(40, cell));
    expect_refused("build", dem, kAssume, {"pixel size " + shown, "outside 0.01..100000 m"});
    std::remove(dem.c_str());
  }
  const std::string dem = write_text("cli_spacing", ".asc", asc_text(40));
  const Outcome r = visvol("build " + dem + " " + kAssume + " --spacing 1e-9 -o /tmp/never.vvp");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("0.01..100000 m"), std::string::npos) << r.err;
  std::remove(dem.c_str());
}

TEST(ImportCli, AnOriginBeyondTheCrsIsRefused) {
  const std::string dem = write_text("cli_far", ".asc", asc_text(40, "30", "1e300"));
  expect_refused("build", dem, kAssume, {"reaches beyond +-100000000 m"});
  std::remove(dem.c_str());
}

TEST(ImportCli, AWarpTooLargeIsRefusedBeforeItStarts) {
  const std::string dem = write_text("cli_oversized", ".asc", asc_text(40));
  // (a band of 2 m: the default 100 m over 1 cm posts is refused first, for its reach)
  expect_refused("build", dem, kAssume + " --spacing 0.01 --tff-offset 2",
                 {"would be 120000 x 120000 posts", "--spacing"});
  std::remove(dem.c_str());
}

}  // namespace
