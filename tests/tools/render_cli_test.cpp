// `visvol render` as users run it: every view from the CSV and the GeoJSON
// `visvol plan` writes and from plain "x y z" text, markers, the help, and
// bad input refused with exit status 2 and a message naming the problem.
#include <dirent.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"

namespace visvol::test {
namespace {

std::vector<unsigned char> bytes_of(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// Width and height from a PNG's IHDR, or {0, 0} when it is not a PNG.
std::pair<int, int> png_size(const std::vector<unsigned char>& b) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() < 24 || !std::equal(kSignature, kSignature + 8, b.begin())) return {0, 0};
  const auto be32 = [&](std::size_t o) { return (b[o] << 24) | (b[o + 1] << 16) | (b[o + 2] << 8) | b[o + 3]; };
  return {be32(16), be32(20)};
}

// Files in a folder whose names contain `part` (temporaries left behind).
int files_containing(const std::string& dir, const std::string& part) {
  int n = 0;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) n += std::string(e->d_name).find(part) != std::string::npos;
    closedir(d);
  }
  return n;
}

// The start and end the "path ..." summary line prints, or NaNs.
struct Ends {
  double start[3], end[3];
};
Ends ends_printed(const std::string& out) {
  Ends e{{NAN, NAN, NAN}, {NAN, NAN, NAN}};
  const std::size_t at = out.find("start (");
  if (at == std::string::npos) return e;
  std::sscanf(out.c_str() + at, "start (%lf, %lf, %lf), end (%lf, %lf, %lf)", &e.start[0], &e.start[1], &e.start[2],
              &e.end[0], &e.end[1], &e.end[2]);
  return e;
}

// The first and last data rows' x_m, y_m, z_m of a plan CSV.
Ends ends_of_csv(const std::string& file) {
  std::ifstream in(file);
  std::string line, first, last;
  // '#' lines (CRS and datums), then the header: index,x_m,y_m,z_m,...
  while (std::getline(in, line) && line.rfind('#', 0) == 0) continue;
  while (std::getline(in, line)) {
    if (first.empty()) first = line;
    last = line;
  }
  Ends e{};
  int index = 0;
  std::sscanf(first.c_str(), "%d,%lf,%lf,%lf", &index, &e.start[0], &e.start[1], &e.start[2]);
  std::sscanf(last.c_str(), "%d,%lf,%lf,%lf", &index, &e.end[0], &e.end[1], &e.end[2]);
  return e;
}

class RenderCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(::testing::TempDir() + "/render_cli_" + std::to_string(getpid()));
    ASSERT_EQ(std::system(("mkdir -p " + *dir_).c_str()), 0);
    pack_ = new std::string(*dir_ + "/small.vvp");
    const Outcome build = visvol("build " + kDem + " " + kSmallPackOptions + " -o " + *pack_);
    ASSERT_EQ(build.status, 0) << build.err;
    // a short real plan: its CSV is what operators hand to render
    const Outcome plan =
        visvol("plan " + *pack_ +
               " --from 550300 4182450 320 --to 550850 4181850 320 --objective hide --vehicle multirotor"
               " --segments 16 --max-seconds 2 -o " +
               *dir_ + "/plan");
    ASSERT_EQ(plan.status, 0) << plan.err;
    std::ofstream(*dir_ + "/points.txt") << "# x y z\n550200 4182500 180\n550600 4182100 160\n551000 4181800 170\n";
  }
  static void TearDownTestSuite() {
    std::system(("rm -rf " + *dir_).c_str());
    delete dir_;
    delete pack_;
  }
  static std::string* dir_;
  static std::string* pack_;
};
std::string* RenderCli::dir_ = nullptr;
std::string* RenderCli::pack_ = nullptr;

TEST_F(RenderCli, EveryViewFromAPlanCsvWritesAPngOfTheAskedSize) {
  for (const char* view : {"oblique", "top", "volume", "slice"}) {
    const std::string out = *dir_ + "/" + view + ".png";
    const Outcome r =
        visvol("render " + *pack_ + " --path " + *dir_ + "/plan.csv --view " + view + " --size 200x150 -o " + out);
    ASSERT_EQ(r.status, 0) << view << ": " << r.err;
    EXPECT_NE(r.out.find("wrote " + out + ": 200 x 150, " + view + " view"), std::string::npos) << r.out;
    EXPECT_EQ(png_size(bytes_of(out)), std::make_pair(200, 150)) << view;
  }
  EXPECT_EQ(files_containing(*dir_, ".tmp"), 0);
}

// The GeoJSON is WGS84: read back into the pack's CRS (UTM 10N) its ends land
// on the CSV's (a centimetre is a millionth of a degree).
TEST_F(RenderCli, PlanGeoJsonIsConvertedBackToThePacksCrs) {
  const Ends csv = ends_of_csv(*dir_ + "/plan.csv");
  for (const char* view : {"top", "slice"}) {
    const std::string out = *dir_ + "/geo_" + view + ".png";
    const Outcome r =
        visvol("render " + *pack_ + " --path " + *dir_ + "/plan.geojson --view " + view + " --size 160x120 -o " + out);
    ASSERT_EQ(r.status, 0) << view << ": " << r.err;
    EXPECT_NE(r.out.find("path  17 points from " + *dir_ + "/plan.geojson (GeoJSON"), std::string::npos) << r.out;
    const Ends geo = ends_printed(r.out);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(geo.start[k], csv.start[k], 0.01) << "start, coordinate " << k;
      EXPECT_NEAR(geo.end[k], csv.end[k], 0.01) << "end, coordinate " << k;
    }
    EXPECT_EQ(png_size(bytes_of(out)), std::make_pair(160, 120));
  }
  const Outcome from_csv = visvol("render " + *pack_ + " --path " + *dir_ + "/plan.csv --view top --size 160x120 -o " +
                                  *dir_ + "/csv_top.png");
  ASSERT_EQ(from_csv.status, 0) << from_csv.err;
  EXPECT_NE(from_csv.out.find("path  17 points from " + *dir_ + "/plan.csv (plan CSV)"), std::string::npos)
      << from_csv.out;
}

// --help documents units, defaults and the transfer file, and its example is
// the default transfer function (drawn the same as no --transfer at all).
TEST_F(RenderCli, HelpDocumentsTheOptionsAndItsTransferExampleIsTheDefault) {
  const Outcome h = visvol("render --help");
  ASSERT_EQ(h.status, 0);
  for (const char* text : {"pixels, 32..4096 a side", "=512x384", "=oblique", "X Y Z (m)", "repeatable",
                           "metres above the ground", "zlib level 0..9", "INT=6", "colour F R G B", "opacity F A",
                           "strictly", "at most 64", "OUT.geojson", "Exit status"}) {
    EXPECT_NE(h.out.find(text), std::string::npos) << text;
  }
  std::istringstream in(h.out);
  std::string line, example;
  while (std::getline(in, line)) {
    const bool point = line.rfind("  colour ", 0) == 0 || line.rfind("  opacity ", 0) == 0;
    if (point && std::isdigit(static_cast<unsigned char>(line[line.find(' ', 2) + 1]))) example += line + "\n";
  }
  EXPECT_EQ(std::count(example.begin(), example.end(), '\n'), 9) << example;
  std::ofstream(*dir_ + "/example.tf") << example;
  const std::string base = "render " + *pack_ + " --view volume --size 120x90 ";
  const Outcome a = visvol(base + "--transfer " + *dir_ + "/example.tf -o " + *dir_ + "/example.png");
  const Outcome b = visvol(base + "-o " + *dir_ + "/no_transfer.png");
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_EQ(bytes_of(*dir_ + "/example.png"), bytes_of(*dir_ + "/no_transfer.png"));
}

TEST_F(RenderCli, PlainTextPathMarkersAndOptionsChangeThePicture) {
  const std::string base = "render " + *pack_ + " --path " + *dir_ + "/points.txt --view top --size 160x120 ";
  const Outcome plain = visvol(base + "-o " + *dir_ + "/plain.png");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_NE(plain.out.find("the path's mean altitude"), std::string::npos) << plain.out;
  const Outcome marked = visvol(base + "--hidden-from 550400 4181900 120 --hidden-from 550800 4182300 120 " +
                                "--visible-to 550300 4181700 250 -o " + *dir_ + "/marked.png");
  ASSERT_EQ(marked.status, 0) << marked.err;
  // a rope bulging 40 m past the pack's east edge (under 5% of its 1170 m) is drawn
  std::ofstream(*dir_ + "/bulge.txt") << "550200 4182500 180\n551200 4182100 160\n551000 4181800 170\n";
  const Outcome bulge = visvol("render " + *pack_ + " --path " + *dir_ + "/bulge.txt --view top --size 160x120 -o " +
                               *dir_ + "/bulge.png");
  EXPECT_EQ(bulge.status, 0) << bulge.err;
  EXPECT_NE(bulge.out.find("path  3 points from " + *dir_ + "/bulge.txt (x y z text)"), std::string::npos) << bulge.out;
  const Outcome height = visvol(base + "--height-above-ground 5 -o " + *dir_ + "/height.png");
  ASSERT_EQ(height.status, 0) << height.err;
  EXPECT_NE(height.out.find("F_p 5 m above the ground"), std::string::npos) << height.out;
  const Outcome stored = visvol(base + "--compression 0 -o " + *dir_ + "/stored.png");
  ASSERT_EQ(stored.status, 0) << stored.err;
  const auto a = bytes_of(*dir_ + "/plain.png"), b = bytes_of(*dir_ + "/marked.png");
  const auto c = bytes_of(*dir_ + "/height.png"), d = bytes_of(*dir_ + "/stored.png");
  EXPECT_EQ(png_size(a), std::make_pair(160, 120));
  EXPECT_NE(a, b);                      // markers drawn
  EXPECT_NE(a, c);                      // another colouring height
  EXPECT_GE(d.size(), 160u * 120 * 3);  // level 0: stored, not compressed
  EXPECT_LT(a.size(), d.size());
}

TEST_F(RenderCli, TransferFunctionFileIsUsedAndItsErrorsNameFileAndLine) {
  const std::string good = *dir_ + "/grey.tf", bad = *dir_ + "/bad.tf";
  std::ofstream(good) << "# grey ramp\ncolour 0 0 0 0\ncolour 1 1 1 1\nopacity 0 0.1\n";
  std::ofstream(bad) << "colour 0 0 0 0\ncolour 1 1 1.5 1\nopacity 0 0.1\n";
  const std::string base = "render " + *pack_ + " --view volume --size 120x90 ";
  const Outcome ok = visvol(base + "--transfer " + good + " -o " + *dir_ + "/grey.png");
  ASSERT_EQ(ok.status, 0) << ok.err;
  const Outcome plain = visvol(base + "-o " + *dir_ + "/default.png");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_NE(bytes_of(*dir_ + "/grey.png"), bytes_of(*dir_ + "/default.png"));
  const Outcome r = visvol(base + "--transfer " + bad + " -o " + *dir_ + "/bad.png");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(bad + ": line 2: G 1.5 is outside [0, 1]"), std::string::npos) << r.err;
  EXPECT_EQ(bytes_of(*dir_ + "/bad.png").size(), 0u);  // nothing written
}

TEST_F(RenderCli, BadInputIsRefusedWithTheReason) {
  std::ofstream(*dir_ + "/flat.txt") << "550200 4182500\n550600 4182100\n";
  std::ofstream(*dir_ + "/far.txt") << "0 0 100\n10 10 100\n";
  std::ofstream(*dir_ + "/short.csv") << "index,x_m,y_m,z_m,fp\n0,550200,4182500,180,0.1\n1,550600,4182100\n";
  std::ofstream(*dir_ + "/fp.csv") << "index,x_m,y_m,z_m,fp\n0,550200,4182500,180,0.1\n1,550600,4182100,160,1.2\n";
  std::ofstream(*dir_ + "/nan.txt") << "550200 4182500 nan\n550600 4182100 160\n";
  std::ofstream(*dir_ + "/nan.csv") << "index,x_m,y_m,z_m\n0,550200,4182500,180\n1,nan,4182100,160\n";
  // the small pack is 1170 m square: a path may stray 5% of that (58 m) outside
  std::ofstream(*dir_ + "/stray.txt") << "550100 4182500 180\n551300 4182100 160\n";
  std::ofstream(*dir_ + "/binary.txt") << "550200 4182500 180\n" << std::string("\x01\x02\xff\xfe", 4) << " abc\n";
  const std::string ls = R"({"type":"LineString","coordinates":)";
  std::ofstream(*dir_ + "/flat.geojson") << ls << "[[-122.43,37.79],[-122.42,37.79]]}";
  std::ofstream(*dir_ + "/point.geojson") << R"({"type":"Point","coordinates":[-122.43,37.79,100]})";
  std::ofstream(*dir_ + "/two.geojson") << R"({"type":"FeatureCollection","features":[)"
                                        << R"({"type":"Feature","properties":{},"geometry":)" << ls
                                        << "[[-122.43,37.79,90],[-122.42,37.79,90]]}},"
                                        << R"({"type":"Feature","properties":{},"geometry":)" << ls
                                        << "[[-122.43,37.79,90],[-122.42,37.79,90]]}}]}";
  std::ofstream(*dir_ + "/lat.geojson") << ls << "[[-122.43,97.79,90],[-122.42,37.79,90]]}";
  std::ofstream(*dir_ + "/nan.geojson") << ls << "[[-122.43,37.79,NaN],[-122.42,37.79,90]]}";
  std::ofstream(*dir_ + "/cut.geojson") << ls << "[[-122.43,37.79,90],[-122.42";
  std::ofstream(*dir_ + "/far.geojson") << ls << "[[2.35,48.85,90],[2.36,48.85,90]]}";  // Paris
  std::ofstream(*dir_ + "/fp.geojson") << R"({"type":"Feature","properties":{"vertex_fp":[0.1]},"geometry":)" << ls
                                       << "[[-122.43,37.79,90],[-122.42,37.79,90]]}}";
  const std::string out = " -o " + *dir_ + "/x.png";
  const std::string p = "render " + *pack_ + " ";
  struct Case {
    std::string args, expected;
  } cases[] = {
      {p + "--size 10x10" + out, "each side must be 32..4096 pixels"},
      {p + "--size 300" + out, "--size '300' is not WIDTHxHEIGHT"},
      {p + "--size 300x-2" + out, "is not WIDTHxHEIGHT"},
      {p + "--view sideways" + out, "sideways"},
      {p + "--view slice" + out, "--view slice needs --path"},
      {p + "--path " + *dir_ + "/flat.txt" + out, "points have no heights"},
      {p + "--path " + *dir_ + "/far.txt" + out, "point 1 (0.0, 0.0) is 4217594 m outside the pack"},
      {p + "--path " + *dir_ + "/short.csv" + out, "short.csv: line 3: 3 columns, the header has 5"},
      {p + "--path " + *dir_ + "/fp.csv" + out, "fp.csv: line 3: fp 1.2 is outside [0, 1]"},
      {p + "--path " + *dir_ + "/missing.txt" + out, "missing.txt"},
      {p + "--path " + *dir_ + out, "is a folder, not a path file"},
      {p + "--path " + *dir_ + "/nan.txt" + out, "nan.txt: line 1: '550200 4182500 nan' is not numbers x y [z]"},
      {p + "--path " + *dir_ + "/nan.csv" + out, "nan.csv: line 3: 'nan' is not a finite number"},
      {p + "--path " + *dir_ + "/stray.txt" + out,
       "stray.txt: point 2 (551300.0, 4182100.0) is 140 m outside the pack"},
      {p + "--path " + *dir_ + "/binary.txt" + out, "binary.txt: line 2: '???? abc' is not numbers"},
      {p + "--path " + *dir_ + "/flat.geojson" + out, "flat.geojson: points have no heights"},
      {p + "--path " + *dir_ + "/point.geojson" + out, "0 LineStrings; a path file has exactly one (found Point)"},
      {p + "--path " + *dir_ + "/two.geojson" + out, "2 LineStrings"},
      {p + "--path " + *dir_ + "/lat.geojson" + out, "coordinates[0]: (-122.430000, 97.790000) is not a WGS84"},
      {p + "--path " + *dir_ + "/nan.geojson" + out, "nan.geojson: not valid JSON"},
      {p + "--path " + *dir_ + "/cut.geojson" + out, "cut.geojson: not valid JSON"},
      {p + "--path " + *dir_ + "/far.geojson" + out, "far.geojson: point 1"},
      {p + "--path " + *dir_ + "/fp.geojson" + out, "properties.vertex_fp is not an array of 2 numbers"},
      {p + "--hidden-from nan 4182100 200" + out, "--hidden-from takes three finite numbers X Y Z"},
      {p + "--hidden-from 550600 4182100 -50" + out, "m below the terrain"},
      {p + "--visible-to 551300 4182100 200" + out, "--visible-to (551300.0, 4182100.0) is 140 m outside the pack"},
      {p + "--height-above-ground -1" + out, "--height-above-ground must be"},
      {p + "--height-above-ground nan" + out, "--height-above-ground must be"},
      {p + "--height-above-ground 1e20" + out, "--height-above-ground must be"},
      {p + "--hidden-from 550600 4182100 1e20" + out, "--hidden-from: Z 1e+20 m is above the 100000 m"},
      {p + "--exaggeration nan" + out, "--exaggeration must be"},
      {p + "--compression 12" + out, "--compression 12 is outside 0..9"},
      {p + "--height-above-ground -5" + out, "--height-above-ground must be"},
      {p + "--fp-max 2" + out, "--fp-max must be"},
      {p + "--visible-to 1 2 3" + out, "--visible-to (1.0, 2.0) is 4217592 m outside the pack"},
      {"render " + *dir_ + "/nope.vvp" + out, "nope.vvp"},
  };
  for (const Case& c : cases) {
    const Outcome r = visvol(c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\ngot: " << r.err;
  }
  EXPECT_EQ(bytes_of(*dir_ + "/x.png").size(), 0u);
  // an output folder that does not exist: a clear failure, no temporary left
  const Outcome r = visvol(p + "-o " + *dir_ + "/no/such/dir/x.png");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("x.png"), std::string::npos) << r.err;
  EXPECT_EQ(files_containing(*dir_, ".tmp"), 0);
}

}  // namespace
}  // namespace visvol::test
