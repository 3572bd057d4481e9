#include "fields/gdal/ascii_grid.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>

#include "fields/gdal/dem_io.hpp"
#include "hostile_rasters.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

bool mentions(const Status& st, const std::string& text) { return st.message().find(text) != std::string::npos; }

TEST(AsciiGrid, ANonNumericCellIsRefusedNamingItsColumnAndRow) {
  // GDAL reads "abc" as 0 m without a word: the red team's "a typo becomes sea level".
  for (const std::string bad : {"abc", "1.2.3", "12m", "--5", "0x", "1e", "nan", "inf", "-infinity"}) {
    const std::string path = write_text("bad_cell", ".asc", asc_text(12, "30", "500000", bad));
    const Result<Heightfield> hf = read_heightfield(path);
    ASSERT_FALSE(hf.ok()) << bad;
    EXPECT_EQ(hf.status().code(), Errc::invalid_argument);
    EXPECT_TRUE(mentions(hf.status(), path)) << hf.status().message();
    EXPECT_TRUE(mentions(hf.status(), "cell (5, 3)")) << hf.status().message();
    EXPECT_TRUE(mentions(hf.status(), "'" + bad + "', not a number")) << hf.status().message();
    std::remove(path.c_str());
  }
}

TEST(AsciiGrid, NumbersInEveryFormGdalReadsStillRead) {
  for (const std::string good : {"1e2", "-3.5", "+7", "104,5", ".5", "-9999"}) {
    const std::string path = write_text("good_cell", ".asc", asc_text(12, "30", "500000", good));
    const Result<Heightfield> hf = read_heightfield(path);
    EXPECT_TRUE(hf.ok() || mentions(hf.status(), "nodata")) << good << ": " << hf.status().message();
    std::remove(path.c_str());
  }
}

TEST(AsciiGrid, AWordTooLongForANumberIsShownCut) {
  const std::string path = write_text("long_cell", ".asc", asc_text(12, "30", "500000", "1" + std::string(100, '0')));
  const Status st = gdal::check_ascii_grid_cells(path, 12, 12);
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st, "...', not a number")) << st.message();
  std::remove(path.c_str());
}

TEST(AsciiGrid, MissingAndExtraCellsAreRefusedWithTheCount) {
  std::string text = asc_text(12);
  const std::string extra = write_text("extra_cells", ".asc", text + "55 66\n");
  Status st = gdal::check_ascii_grid_cells(extra, 12, 12);
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st, "has 146 cells after its header; its size 12 x 12 needs 144")) << st.message();
  text.resize(text.rfind(' '));  // the last cell gone
  const std::string missing = write_text("missing_cells", ".asc", text + "\n");
  st = gdal::check_ascii_grid_cells(missing, 12, 12);
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(mentions(st, "has 143 cells")) << st.message();
  std::remove(extra.c_str());
  std::remove(missing.c_str());
}

TEST(AsciiGrid, GrassNullTokenIsNodataNotABadCell) {
  std::string text = "north: 4000360\nsouth: 4000000\neast: 500360\nwest: 500000\nrows: 12\ncols: 12\nnull: *\n";
  for (int j = 0; j < 12; ++j) {
    for (int i = 0; i < 12; ++i) text += (i == 4 && j == 4) ? "* " : "120 ";
    text += "\n";
  }
  const std::string path = write_text("grass_null", ".asc", text);
  EXPECT_TRUE(gdal::check_ascii_grid_cells(path, 12, 12).ok());
  // Read as the one nodata post it is.
  const Result<Heightfield> hf = read_heightfield(path);
  ASSERT_FALSE(hf.ok());
  EXPECT_TRUE(mentions(hf.status(), "1 posts are nodata")) << hf.status().message();
  EXPECT_TRUE(read_heightfield(path, {NodataPolicy::fill}).ok());
  std::remove(path.c_str());
}

TEST(AsciiGrid, ANonNumericNodataValueIsRefusedNamingIt) {
  // GDAL reads a nodata value of "abc" as 0 and takes every post of 0 m (sea
  // level, a lake) for a hole; a cell of "abc" is then a hole too.
  for (const std::string bad : {"abc", "-99x", "1.2.3", "inf"}) {
    std::string text = asc_text(12, "30", "500000", "0");
    text.replace(text.find("-9999"), 5, bad);
    const std::string path = write_text("bad_nodata", ".asc", text);
    const Result<Heightfield> hf = read_heightfield(path);
    ASSERT_FALSE(hf.ok()) << bad;
    EXPECT_EQ(hf.status().code(), Errc::invalid_argument);
    EXPECT_TRUE(mentions(hf.status(), path)) << hf.status().message();
    EXPECT_TRUE(mentions(hf.status(), "nodata value '" + bad + "' is not a finite number")) << hf.status().message();
    std::remove(path.c_str());
  }
  // A number stays accepted (GRASS's own null marker too: the case below).
  std::string text = asc_text(12, "30", "500000", "0");
  text.replace(text.find("-9999"), 5, "-32768.5");
  const std::string path = write_text("good_nodata", ".asc", text);
  const Result<Heightfield> hf = read_heightfield(path);
  ASSERT_TRUE(hf.ok()) << hf.status().message();
  EXPECT_EQ(hf.value().at(5, 3), 0.0f);  // the post of 0 m is a height, not a hole
  std::remove(path.c_str());
}

TEST(AsciiGrid, TheSharedRealGridsPass) {
  const std::string dir = std::string(VISVOL_SHARED_DATA) + "/dem/";
  const std::string esri = dir + "boulder_srtm3_404x404.asc";
  const std::string grass = dir + "grass_viewshed_reference/elevation.ascii";
  if (access(esri.c_str(), R_OK) != 0) GTEST_SKIP() << esri << " not found";
  EXPECT_TRUE(gdal::check_ascii_grid_cells(esri, 404, 404).ok());
  EXPECT_TRUE(gdal::check_ascii_grid_cells(grass, 222, 147).ok());
}

}  // namespace
}  // namespace visvol::fields
