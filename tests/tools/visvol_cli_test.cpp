// The visvol command as users run it: exit statuses, messages, outputs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../fields/gdal/hostile_rasters.hpp"
#include "../support/scratch.hpp"
#include "cli_runner.hpp"

namespace {

using visvol::test::kCrop;
using visvol::test::kDem;
using visvol::test::kSmallPackOptions;
using visvol::test::Outcome;
using visvol::test::slurp;
using visvol::test::visvol;

class Cli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pack_ = new std::string(::testing::TempDir() + "/cli_" + std::to_string(getpid()) + ".vvp");
    const Outcome r = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + *pack_);
    ASSERT_EQ(r.status, 0) << r.err;
  }
  static void TearDownTestSuite() {
    std::remove(pack_->c_str());
    delete pack_;
  }
  static std::string* pack_;
};
std::string* Cli::pack_ = nullptr;

TEST(CliUsage, HelpListsCommandsAndExitsZero) {
  const Outcome r = visvol("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* c : {"build", "info", "verify", "sample", "viewshed", "export"}) {
    EXPECT_NE(r.out.find(c), std::string::npos) << c;
  }
  for (const char* c : {"build", "info", "verify", "sample", "viewshed", "export"}) {
    const Outcome h = visvol(std::string(c) + " --help");
    EXPECT_EQ(h.status, 0) << c;
    EXPECT_NE(h.out.find("Usage"), std::string::npos) << c;
  }
}

TEST(CliUsage, BadArgumentsExitTwoWithOneLine) {
  for (const char* args : {"", "build", "frobnicate", "build x.tif --levels abc", "sample"}) {
    const Outcome r = visvol(args);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
  }
  const Outcome unknown = visvol("frobnicate x.vvp");
  EXPECT_NE(unknown.err.find("unknown command 'frobnicate' (commands: build, check, export, info, plan, render, "
                             "sample, verify, viewshed; try --help)"),
            std::string::npos)
      << unknown.err;
  EXPECT_NE(visvol("").err.find("A subcommand is required"), std::string::npos) << "nothing given: CLI11's words";
  // an empty value was read as the option's default (a plan at 30 m clearance)
  const Outcome empty = visvol("plan x.vvp --objective hide --clearance '' -o out");
  EXPECT_EQ(empty.status, 2);
  EXPECT_NE(empty.err.find("argument 6 after --clearance is empty"), std::string::npos) << empty.err;
  // and `--clearance=`, which CLI11 gives the next argument
  const Outcome equals = visvol("plan x.vvp --objective hide --clearance= 45 -o out");
  EXPECT_EQ(equals.status, 2);
  EXPECT_NE(equals.err.find("argument 5, '--clearance=', has an empty value"), std::string::npos) << equals.err;
  // numbers are decimal: "--segments 010" was octal eight, "0x10" sixteen
  const Outcome hex = visvol("plan x.vvp --objective hide --from 0 0 0 --to 1 1 1 --segments 0x10 -o out");
  EXPECT_EQ(hex.status, 2);
  EXPECT_NE(hex.err.find("--segments: '0x10' is not a whole number in decimal digits"), std::string::npos) << hex.err;
  const Outcome hex_real = visvol("plan x.vvp --objective hide --from 0 0 0 --to 1 1 1 --speed 0x10 -o out");
  EXPECT_EQ(hex_real.status, 2);
  EXPECT_NE(hex_real.err.find("--speed: '0x10' is not a number in decimal"), std::string::npos) << hex_real.err;
}

TEST(CliUsage, BadInputNamesTheFile) {
  const Outcome r = visvol("build /nonexistent/dem.tif -o /tmp/never.vvp");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/nonexistent/dem.tif"), std::string::npos);
  const Outcome levels = visvol("build " + kDem + " " + kCrop + " --levels 400 -o /tmp/never.vvp");
  EXPECT_EQ(levels.status, 2);
  EXPECT_NE(levels.err.find("levels: 400"), std::string::npos) << levels.err;
  EXPECT_NE(access("/tmp/never.vvp", F_OK), 0);
  // a grid --max-memory cannot hold, refused before the import reads it (1 m
  // posts of this DEM took 3 GB in 13 s to be refused, 9 GB under 8 GiB)
  const Outcome big = visvol("build " + kDem + " --fill-nodata --spacing 1 --max-memory 1024 -o /tmp/never.vvp");
  EXPECT_EQ(big.status, 2);
  EXPECT_NE(big.err.find("the import would be 11100 x 13980 posts at 1 m spacing"), std::string::npos) << big.err;
  EXPECT_NE(big.err.find("(--max-memory 1024 MiB at 48 bytes a post)"), std::string::npos) << big.err;
}

TEST_F(Cli, InfoJsonHasTheGeoreference) {
  const Outcome r = visvol("info " + *pack_ + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["nx"], 40);
  EXPECT_EQ(j["ny"], 40);
  EXPECT_EQ(j["nz"], 16);
  EXPECT_DOUBLE_EQ(j["cell_size_m"].get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(j["origin_x"].get<double>(), 549990.0);  // centre of the north-west pixel
  EXPECT_DOUBLE_EQ(j["origin_y"].get<double>(), 4182750.0);
  EXPECT_EQ(j["levels_of_detail"], 2);
  EXPECT_NE(j["crs_wkt"].get<std::string>().find("UTM zone 10N"), std::string::npos);
  EXPECT_EQ(j["build"]["range_posts"], 8);
  for (const char* key : {"z0_m", "dz_m", "source"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["source"]["sha256"].get<std::string>().size(), 64u);
}

// The suite's pack: 40 x 40 posts of 30 m from (549990, 4182750), range 8
// posts: planning bounds 240 m inside the posts.
TEST_F(Cli, InfoShowsTheRecordedPlanningBounds) {
  const Outcome r = visvol("info " + *pack_ + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json b = nlohmann::json::parse(r.out)["planning_bounds"];
  EXPECT_DOUBLE_EQ(b["xmin_m"].get<double>(), 550230.0);
  EXPECT_DOUBLE_EQ(b["ymin_m"].get<double>(), 4181820.0);
  EXPECT_DOUBLE_EQ(b["xmax_m"].get<double>(), 550920.0);
  EXPECT_DOUBLE_EQ(b["ymax_m"].get<double>(), 4182510.0);
  EXPECT_DOUBLE_EQ(b["margin_m"].get<double>(), 240.0);
  EXPECT_EQ(b["recorded"], true);
  const Outcome text = visvol("info " + *pack_);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("planning   x 550230.00..550920.00, y 4181820.00..4182510.00 (margin 240 m)\n"),
            std::string::npos)
      << text.out;
}

TEST_F(Cli, InfoDescribesADem) {
  const Outcome r = visvol("info " + kDem + " --fill-nodata");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("370 x 466 posts, 30.00 m spacing"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("heights 0.0..343.0 m"), std::string::npos);
  // its import is held to --max-memory, refused from the header (a 3.4 KB
  // GeoTIFF of 16384 x 16384 posts took 2.4 GB to describe)
  const Outcome small = visvol("info " + kDem + " --fill-nodata --max-memory 1");
  EXPECT_EQ(small.status, 2) << small.err;
  EXPECT_NE(small.err.find("370 x 466 posts is more than the 65536 this read allows (--max-memory 1 MiB"),
            std::string::npos)
      << small.err;
}

TEST_F(Cli, VerifyPassesThenNamesTheCorruptTile) {
  EXPECT_EQ(visvol("verify " + *pack_).status, 0);
  const std::string bad = *pack_ + ".bad";
  {
    std::ifstream in(*pack_, std::ios::binary);
    std::vector<char> bytes{std::istreambuf_iterator<char>(in), {}};
    bytes[4096 + 17] ^= 1;  // inside the first tile: level 0's first height tile
    std::ofstream(bad, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const Outcome r = visvol("verify " + bad);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("height tile (0, 0) of level 0"), std::string::npos) << r.err;
  std::remove(bad.c_str());
}

TEST_F(Cli, SampleAnswersLineByLine) {
  const std::string points =
      "550500 4182000 200\n"
      "550500 4182000 5000\n"
      "not a point\n"
      "1 2 3\n";
  const Outcome r = visvol("sample " + *pack_, points);
  EXPECT_EQ(r.status, 2);  // two bad lines
  std::istringstream lines(r.out);
  std::string a, b, c, d;
  ASSERT_TRUE(std::getline(lines, a) && std::getline(lines, b) && std::getline(lines, c) && std::getline(lines, d));
  EXPECT_GT(std::stod(b), 0.0);  // high above everything sees a lot
  EXPECT_GE(std::stod(b), std::stod(a));
  EXPECT_EQ(c, "nan");
  EXPECT_EQ(d, "nan");
  EXPECT_NE(r.err.find("line 3"), std::string::npos);
  EXPECT_NE(r.err.find("line 4"), std::string::npos);
  EXPECT_NE(r.err.find("outside the pack"), std::string::npos);
  const Outcome g = visvol("sample " + *pack_ + " --layer gradient", "550500 4182000 200\n");
  EXPECT_EQ(g.status, 0);
  std::istringstream parts(g.out);
  double gx, gy, gz;
  EXPECT_TRUE(parts >> gx >> gy >> gz);
  const Outcome h = visvol("sample " + *pack_ + " --layer height --lod 1", "550500 4182000 0\n");
  EXPECT_EQ(h.status, 0);
  EXPECT_GT(std::stod(h.out), 0.0);
  EXPECT_EQ(visvol("sample " + *pack_ + " --layer fp", "").status, 2);
  EXPECT_EQ(visvol("sample " + *pack_ + " --lod 7", "").status, 2);
  // a line without end (/dev/zero grew one to gigabytes): refused at 4 KiB,
  // after the points before it were answered
  const Outcome endless = visvol("sample " + *pack_, "550500 4182000 200\n" + std::string(5000, '7'));
  EXPECT_EQ(endless.status, 2);
  EXPECT_EQ(std::count(endless.out.begin(), endless.out.end(), '\n'), 1);
  EXPECT_NE(endless.err.find("stdin line 2 is longer than 4096 bytes"), std::string::npos) << endless.err;
  // results written to a full disk are lost: never exit 0 (sample and info did)
  for (const std::string& command : {"sample " + *pack_, "info " + *pack_}) {
    const Outcome full = visvol::test::run_command(
        "sh -c '" + std::string(VISVOL_BIN) + " " + command + " > /dev/full'", "550500 4182000 200\n");
    EXPECT_EQ(full.status, 1) << command;
    EXPECT_NE(full.err.find("writing the standard output failed"), std::string::npos) << command << ": " << full.err;
  }
}

TEST_F(Cli, ExportWritesAVolume) {
  const std::string out = *pack_ + ".mhd";
  const Outcome r = visvol("export " + *pack_ + " --layer visibility --format mhd -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream in(out);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "ObjectType = Image");
  std::remove(out.c_str());
  EXPECT_EQ(visvol("export " + *pack_ + " --layer visibility --format nrrd -o " + out).status, 2);
}

TEST_F(Cli, PlanWritesThePathInFourFormats) {
  const std::string base = *pack_ + "_plan";
  const Outcome r = visvol("plan " + *pack_ +
                           " --from 550300 4182450 150 --to 550850 4181850 150 --objective hide"
                           " --vehicle multirotor --init straight --segments 32 --max-seconds 5 --json -o " +
                           base);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_LT(summary["fc_end"].get<double>(), summary["fc_start"].get<double>());
  EXPECT_GE(summary["min_clearance_m"].get<double>(), 30.0);
  const nlohmann::json gj = nlohmann::json::parse(slurp(base + ".geojson"));
  const nlohmann::json& coords = gj["features"][0]["geometry"]["coordinates"];
  EXPECT_EQ(gj["features"][0]["geometry"]["type"], "LineString");
  // the rope's 33 and any the envelope fit added, less those thinned away
  EXPECT_GE(summary["fitted_vertices"].get<int>(), 33);
  ASSERT_EQ(coords.size(), summary["vertices"].get<std::size_t>());
  ASSERT_GE(coords.size(), 2u);
  EXPECT_NEAR(coords[0][0].get<double>(), -122.43, 0.1);  // San Francisco, WGS84 longitude
  EXPECT_NEAR(coords[0][1].get<double>(), 37.79, 0.1);
  // RFC 7946: above the WGS84 ellipsoid, EGM96's geoid being about 32 m under it here
  EXPECT_DOUBLE_EQ(gj["features"][0]["properties"]["vertex_height_orthometric_m"][0].get<double>(), 150.0);
  EXPECT_NEAR(coords[0][2].get<double>(), 150.0 - 32.0, 2.0);
  const nlohmann::json plan = nlohmann::json::parse(slurp(base + ".plan"));
  EXPECT_EQ(plan["fileType"], "Plan");
  // multirotor: takeoff, the waypoints, land
  EXPECT_EQ(plan["mission"]["items"].size(), coords.size() + 2);
  EXPECT_EQ(plan["mission"]["items"][0]["command"], 22);
  EXPECT_EQ(plan["mission"]["items"][1]["frame"], 0);  // MAV_FRAME_GLOBAL: above mean sea level
  EXPECT_EQ(plan["mission"]["items"][1]["command"], 16);
  EXPECT_DOUBLE_EQ(plan["mission"]["items"][1]["params"][6].get<double>(), 150.0);
  const std::string kml = slurp(base + ".kml");
  EXPECT_NE(kml.find("<altitudeMode>absolute</altitudeMode>"), std::string::npos);
  // '#' lines naming the CRS and datums, the header, 33 rows
  std::istringstream csv(slurp(base + ".csv"));
  int rows = 0;
  for (std::string line; std::getline(csv, line);) rows += !line.empty() && line[0] != '#';
  EXPECT_EQ(rows, static_cast<int>(coords.size()) + 1);
  for (const char* ext : {".geojson", ".csv", ".kml", ".plan"}) std::remove((base + ext).c_str());
}

// `visvol plan --init` takes the CSV and the GeoJSON a plan wrote: the rope
// starts on that path (the same F_c and length it ended with), not on a
// straight line.
TEST_F(Cli, PlanStartsFromTheCsvOrGeoJsonOfAnEarlierPlan) {
  const std::string base = *pack_ + "_first", again = *pack_ + "_again";
  const std::string ends = " --from 550300 4182450 150 --to 550850 4181850 150 --objective hide --vehicle multirotor";
  const Outcome first =
      visvol("plan " + *pack_ + ends + " --init straight --segments 32 --max-seconds 5 --json -o " + base);
  ASSERT_EQ(first.status, 0) << first.err;
  const nlohmann::json a = nlohmann::json::parse(first.out);
  for (const char* format : {".csv", ".geojson"}) {
    SCOPED_TRACE(format);
    const Outcome second = visvol("plan " + *pack_ + ends + " --init " + base + format +
                                  " --segments 32 --max-seconds 1 --json -o " + again);
    ASSERT_EQ(second.status, 0) << second.err;
    const nlohmann::json b = nlohmann::json::parse(second.out);
    EXPECT_NEAR(b["fc_start"].get<double>(), a["fc_end"].get<double>(), 1e-4 * a["fc_end"].get<double>());
    EXPECT_NEAR(b["length_start_m"].get<double>(), a["length_m"].get<double>(), 0.1);
    // not the straight line
    EXPECT_GT(std::fabs(b["length_start_m"].get<double>() - a["length_start_m"].get<double>()), 10.0);
  }
  for (const std::string& f : {base, again}) {
    for (const char* ext : {".geojson", ".csv", ".kml", ".plan"}) std::remove((f + ext).c_str());
  }
}

TEST_F(Cli, PlanRefusesBadRequests) {
  const std::string base = *pack_ + "_bad";
  const std::string ok_ends = " --from 550300 4182450 150 --to 550850 4181850 150";
  for (const std::string& args :
       {std::string(" --from 1 2 250 --to 551050 4181700 250 --objective hide"), ok_ends + " --objective sideways",
        ok_ends + " --objective hide --segments 0", ok_ends + " --objective hide --init /nonexistent/path.txt",
        std::string(" --from 550300 4182450 -900 --to 550850 4181850 320 --objective hide")}) {
    const Outcome r = visvol("plan " + *pack_ + args + " -o " + base);
    EXPECT_EQ(r.status, 2) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
  }
  EXPECT_NE(access((base + ".csv").c_str(), F_OK), 0);
}

// A 2D --init is lifted over the terrain every half post: a path zigzagging
// across the pack thousands of times is refused, not lifted to gigabytes.
TEST_F(Cli, PlanRefusesAnInitPathTooLongToLift) {
  const std::string init = *pack_ + "_zigzag.txt";
  {
    std::ofstream out(init);
    for (int k = 0; k < 40000; ++k) out << (k % 2 ? "550850 4181850\n" : "550300 4182450\n");
  }
  const Outcome r = visvol("plan " + *pack_ + " --from 550300 4182450 150 --to 550850 4181850 150 --init " + init +
                           " --objective hide -o " + *pack_ + "_zigzag");
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--init " + init + ": 40000 points"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("trace a shorter path"), std::string::npos) << r.err;
  std::remove(init.c_str());
}

// `build --area`: the pack's planning bounds hold the area, and the DEM is
// cropped to little more than the area and its margin.
class CliArea : public ::testing::Test {
 protected:
  static constexpr double kArea[4] = {550100, 4181300, 550900, 4182100};
  static std::string area() { return " --area 550100 4181300 550900 4182100"; }
  static std::string options() { return " --fill-nodata --levels 16 --lod 1 --range 8 --tff-offset 60 --tff-levels 6"; }

  // Builds with `args`, returns `info --json` of the pack.
  nlohmann::json build_and_info(const std::string& args) {
    const Outcome r = visvol("build " + kDem + options() + args + " -o " + pack_);
    EXPECT_EQ(r.status, 0) << args << ": " << r.err;
    const Outcome info = visvol("info " + pack_ + " --json");
    EXPECT_EQ(info.status, 0) << info.err;
    std::remove(pack_.c_str());
    return info.status == 0 ? nlohmann::json::parse(info.out) : nlohmann::json::object();
  }
  static void expect_holds_area(const nlohmann::json& b) {
    EXPECT_EQ(b["recorded"], true);
    EXPECT_LE(b["xmin_m"].get<double>(), kArea[0]);
    EXPECT_LE(b["ymin_m"].get<double>(), kArea[1]);
    EXPECT_GE(b["xmax_m"].get<double>(), kArea[2]);
    EXPECT_GE(b["ymax_m"].get<double>(), kArea[3]);
  }
  // Posts a side the area and its margin need, and at most two more.
  static void expect_snug(const nlohmann::json& info, double margin_m) {
    const double spacing_m = info["cell_size_m"].get<double>();
    const double need = (kArea[2] - kArea[0] + 2 * margin_m) / spacing_m + 1;
    EXPECT_GE(info["nx"].get<double>(), need);
    EXPECT_LE(info["nx"].get<double>(), need + 2);
    EXPECT_GE(info["ny"].get<double>(), need);
    EXPECT_LE(info["ny"].get<double>(), need + 2);
  }

  const std::string pack_ = ::testing::TempDir() + "/cli_area_" + std::to_string(getpid()) + ".vvp";
};

TEST_F(CliArea, PlanningBoundsHoldTheAreaWithTheRangeMargin) {
  const nlohmann::json info = build_and_info(area());
  const nlohmann::json& b = info["planning_bounds"];
  EXPECT_DOUBLE_EQ(b["margin_m"].get<double>(), 240.0);  // 8 posts of 30 m
  expect_holds_area(b);
  expect_snug(info, 240.0);
  EXPECT_EQ(info["source"]["import"]["area"], nlohmann::json(std::vector<double>(kArea, kArea + 4)));
}

TEST_F(CliArea, ResampledAndReprojectedImportsHoldTheAreaToo) {
  const nlohmann::json resampled = build_and_info(area() + " --spacing 60");
  EXPECT_DOUBLE_EQ(resampled["cell_size_m"].get<double>(), 60.0);
  EXPECT_DOUBLE_EQ(resampled["planning_bounds"]["margin_m"].get<double>(), 480.0);
  expect_holds_area(resampled["planning_bounds"]);
  expect_snug(resampled, 480.0);
  const nlohmann::json projected = build_and_info(area() + " --t-srs EPSG:32610");  // NAD27 to WGS 84
  EXPECT_NE(projected["crs_name"].get<std::string>().find("WGS 84"), std::string::npos);
  expect_holds_area(projected["planning_bounds"]);
}

TEST_F(CliArea, GivenAndUnrangedMarginsAreRecorded) {
  const nlohmann::json given = build_and_info(area() + " --planning-margin 100");
  EXPECT_DOUBLE_EQ(given["planning_bounds"]["margin_m"].get<double>(), 100.0);
  expect_holds_area(given["planning_bounds"]);
  expect_snug(given, 100.0);
  // none: an eighth of the DEM's smaller side, which the crop makes a sixth of the area's
  const nlohmann::json none = build_and_info(area() + " --range-shape none");
  const nlohmann::json& b = none["planning_bounds"];
  EXPECT_NEAR(b["margin_m"].get<double>(), 800.0 / 6.0, 1e-9);
  expect_holds_area(b);
  const double smaller_side_m = (std::min(none["nx"].get<int>(), none["ny"].get<int>()) - 1) * 30.0;
  // the crop is snapped to whole pixels: two posts more at most
  EXPECT_NEAR(b["margin_m"].get<double>(), smaller_side_m / 8.0, 2 * 30.0 / 8.0);
}

// Exit 2 with one line that names the problem; no pack written.
void expect_refused(const std::string& args, const std::vector<std::string>& named) {
  const std::string out = ::testing::TempDir() + "/cli_refused_" + std::to_string(getpid()) + ".vvp";
  const Outcome r = visvol("build " + kDem + " --fill-nodata --levels 16 --lod 1" + args + " -o " + out);
  EXPECT_EQ(r.status, 2) << args << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
  for (const std::string& n : named) EXPECT_NE(r.err.find(n), std::string::npos) << args << ": " << r.err;
  EXPECT_NE(access(out.c_str(), F_OK), 0) << args;
}

TEST(CliBuildRefuses, AreaWithCropOrNotABox) {
  expect_refused(" --range 8 --area 550100 4181300 550900 4182100 " + kCrop, {"--area and --crop"});
  expect_refused(" --range 8 --area 550900 4181300 550100 4182100", {"--area", "not a box"});
  expect_refused(" --range 8 --area 550100 nan 550900 4182100", {"--area", "finite"});
  expect_refused(" --range 8 --area 550100 4181300 inf 4182100", {"--area", "finite"});
}

TEST(CliBuildRefuses, AreaTheDemDoesNotCover) {
  // The DEM's posts end at x 555060: the area needs them to 554900 + 240 m.
  expect_refused(" --range 8 --area 554100 4181300 554900 4182100", {"--area", "80.0 m short on the east side"});
  expect_refused(" --range 8 --area 543000 4170000 544000 4192500",
                 {"m short on the west side", "m short on the south side", "m short on the north side"});
}

TEST(CliBuildRefuses, BadMarginsAndEmptyBounds) {
  expect_refused(" --range 8 " + kCrop + " --planning-margin -1", {"--planning-margin", "-1"});
  expect_refused(" --range 8 " + kCrop + " --planning-margin nan", {"--planning-margin"});
  // 20 posts of range leave nothing of the 1170 m of posts of the crop
  expect_refused(" " + kCrop + " --range 20", {"1170 x 1170 m", "--planning-margin", "--range"});
  expect_refused(" " + kCrop + " --range-shape none --planning-margin 585", {"1170 x 1170 m", "--planning-margin"});
}

TEST(CliBuildRefuses, ATerrainForceBandOfNothing) {
  // a band of 1e-300 m was built (every sample 0: no push off the ground)
  for (const char* offset : {"1e-300", "0.5", "0", "-1", "nan", "inf", "301"})
    expect_refused(" --range 8 " + kCrop + " --tff-offset " + offset, {"--tff-offset", "1..300 m"});
  for (const char* levels : {"1", "0", "-1", "65"})
    expect_refused(" --range 8 " + kCrop + " --tff-levels " + levels, {"--tff-levels", "2..64"});
  // and before anything is built, with no pack to write
  const Outcome r =
      visvol("build " + kDem + " --fill-nodata --levels 16 --lod 1 --range 8 " + kCrop + " --tff-offset 1e-300");
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--tff-offset"), std::string::npos) << r.err;
  // a band of too many posts: refused before the import when --spacing sets them
  expect_refused(" --range 8 " + kCrop + " --spacing 0.3", {"terrain force band", "335 posts", "--tff-offset"});
}

TEST(CliBuildRefuses, ADemThatIsNoPlaceOnEarth) {
  // a UTM grid 90,000 km north: it built, and every plan on it failed at its WGS84 step
  visvol::fields::testing::TiffSpec far;
  far.gt[0] = far.gt[3] = 9e7;
  far.epsg = 32610;
  const std::string dem = visvol::fields::testing::write_hostile_tiff("cli_far", far);
  const std::string out = ::testing::TempDir() + "/cli_far_" + std::to_string(getpid()) + ".vvp";
  const Outcome r = visvol("build " + dem + " --levels 16 --lod 1 --range 2 -o " + out);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find(dem + ": its north-west post (90000015.00, 89999985.00) is no place on Earth in its CRS "
                             "(WGS 84 / UTM zone 10N)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(access(out.c_str(), F_OK), 0);
  // the same grid where UTM zone 10N has it, and one without a CRS (local metres), build
  far.gt[0] = 500000;
  far.gt[3] = 4001000;
  const std::string placed = visvol::fields::testing::write_hostile_tiff("cli_placed", far);
  far.epsg = 0;
  const std::string local = visvol::fields::testing::write_hostile_tiff("cli_local", far);
  for (const std::string& d : {placed, local}) {
    const Outcome ok = visvol("build " + d + " --levels 16 --lod 1 --range 2 -o " + out);
    EXPECT_EQ(ok.status, 0) << d << ": " << ok.err;
    std::remove(out.c_str());
  }
  for (const std::string& d : {dem, placed, local}) std::remove(d.c_str());
  // a site grid's local CRS: built, and told that plans on it give no WGS84 positions
  const std::string site = ::testing::TempDir() + "/cli_site_" + std::to_string(getpid());
  std::ofstream(site + ".asc") << visvol::fields::testing::asc_text(12);
  std::ofstream(site + ".prj")
      << "LOCAL_CS[\"site grid\",LOCAL_DATUM[\"site\",0],UNIT[\"metre\",1],AXIS[\"X\",EAST],AXIS[\"Y\",NORTH]]";
  const Outcome local_crs = visvol("build " + site + ".asc --levels 16 --lod 1 --range 2 -o " + out);
  EXPECT_EQ(local_crs.status, 0) << local_crs.err;
  EXPECT_NE(local_crs.err.find("warning: " + site + ".asc: its CRS (site grid) is not a projected CRS in metres"),
            std::string::npos)
      << local_crs.err;
  EXPECT_NE(local_crs.err.find("plans on this pack give no WGS84 positions"), std::string::npos) << local_crs.err;
  for (const char* ext : {".asc", ".prj"}) std::remove((site + ext).c_str());
  std::remove(out.c_str());
}

TEST(CliViewshed, WritesAGeoTiff) {
  const std::string out = ::testing::TempDir() + "/cli_vs_" + std::to_string(getpid()) + ".tif";
  const Outcome r = visvol("viewshed " + kDem + " " + kCrop + " --observer 550500 4182000 -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("visible"), std::string::npos);
  EXPECT_EQ(access(out.c_str(), R_OK), 0);
  std::remove(out.c_str());
  const Outcome outside = visvol("viewshed " + kDem + " " + kCrop + " --observer 0 0 -o " + out);
  EXPECT_EQ(outside.status, 2);
  EXPECT_NE(outside.err.find("outside the DEM"), std::string::npos);
}

}  // namespace

namespace {

// A pack build gives its summary as JSON too (--json and --json-file were
// ignored with -o), and a bad --json-file is refused before the build, by
// name (it was found only once the build had run).
TEST(CliBuild, APackBuildsSummaryIsJsonWhenAsked) {
  const std::string out = visvol::test::scratch_path("cli_json_pack");
  const std::string summary = visvol::test::scratch_path("cli_json_summary");
  const Outcome r = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + out + " --json --json-file " + summary);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json printed = nlohmann::json::parse(r.out);
  EXPECT_EQ(printed["pack"]["path"], out);
  EXPECT_GT(printed["pack"]["bytes"].get<double>(), 0);
  EXPECT_EQ(printed["levels_of_detail"].size(), 2u);
  EXPECT_TRUE(printed["planning_bounds"].contains("margin_m"));
  EXPECT_EQ(nlohmann::json::parse(slurp(summary)), printed);
  std::remove(out.c_str());
  std::remove(summary.c_str());

  const std::string never = visvol::test::scratch_path("cli_json_never");
  const Outcome bad =
      visvol("build " + kDem + " " + kSmallPackOptions + " -o " + never + " --json-file /nonexistent/dir/summary.json");
  EXPECT_EQ(bad.status, 2) << bad.err;
  EXPECT_NE(bad.err.find("--json-file"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find("building"), std::string::npos) << "refused before the build: " << bad.err;
  EXPECT_NE(access(never.c_str(), F_OK), 0);
  // the summary over the pack it describes: refused, by name
  const Outcome over = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + never + " --json-file " + never);
  EXPECT_EQ(over.status, 2) << over.err;
  EXPECT_NE(over.err.find("is the pack's -o"), std::string::npos) << over.err;
  EXPECT_NE(access(never.c_str(), F_OK), 0);
}

}  // namespace

namespace {

// A pack cut short while a command reads it (an operator's cp over it): the
// next read of a mapped page faults. One line and exit 1 ("Bus error",
// status 135, before).
TEST_F(Cli, APackCutShortWhileReadIsSaidNotACrash) {
  const std::string live = visvol::test::scratch_path("cli_live_pack");
  const std::string err = visvol::test::scratch_path("cli_live_err");
  ASSERT_EQ(std::system(("cp " + *pack_ + " " + live).c_str()), 0);
  const Outcome info = visvol("info " + live + " --json");
  ASSERT_EQ(info.status, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out);
  const nlohmann::json& b = j["planning_bounds"];
  const double x = 0.5 * (b["xmin_m"].get<double>() + b["xmax_m"].get<double>());
  const double y = 0.5 * (b["ymin_m"].get<double>() + b["ymax_m"].get<double>());
  const std::string out = visvol::test::scratch_path("cli_live_out");
  FILE* sample = ::popen((std::string(VISVOL_BIN) + " sample " + live + " >" + out + " 2>" + err).c_str(), "w");
  ASSERT_NE(sample, nullptr);
  std::fprintf(sample, "%.2f %.2f 300\n", x, y);
  std::fflush(sample);
  // the first point answered: the pack is open and mapped (30 s at most, a
  // sanitizer build on a loaded machine)
  for (int k = 0; k < 300 && slurp(out).find('\n') == std::string::npos; ++k) ::usleep(100 * 1000);
  ASSERT_NE(slurp(out).find('\n'), std::string::npos) << slurp(err);
  ASSERT_EQ(::truncate(live.c_str(), 0), 0);
  std::fprintf(sample, "%.2f %.2f 200\n", x + 100, y - 100);
  const int status = ::pclose(sample);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_NE(slurp(err).find("(a pack, or a DEM) was cut short or rewritten while this command read it"),
            std::string::npos)
      << slurp(err);
  std::remove(live.c_str());
  std::remove(err.c_str());
  std::remove(out.c_str());
}

}  // namespace
