#include "storage/volume_export.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "../fields/terrains.hpp"
#include "storage/pack_build.hpp"

namespace visvol::storage {
namespace {

using namespace visvol::fields::testing;

class Export : public ::testing::Test {
 protected:
  void SetUp() override {
    hf_ = fractal(21, 8);
    path_ = ::testing::TempDir() + "/export_" + std::to_string(getpid()) + ".vvp";
    PackBuildParams p;
    p.field.nz = 10;
    p.field.range_posts = 6;
    p.lod_levels = 1;
    p.tff.band_offset_m = 40;
    p.tff.band_levels = 6;
    ASSERT_TRUE(build_pack(hf_, p, "", path_).ok());
    Result<std::shared_ptr<const Pack>> pack = Pack::open(path_);
    ASSERT_TRUE(pack.ok());
    Result<PackLevel> level = PackLevel::open(*pack, 0);
    ASSERT_TRUE(level.ok());
    level_ = std::make_unique<PackLevel>(std::move(*level));
  }
  void TearDown() override { std::remove(path_.c_str()); }
  fields::Heightfield hf_;
  std::string path_;
  std::unique_ptr<PackLevel> level_;
};

TEST_F(Export, AxesAreWorldAxesFromTheSouthWest) {
  const ExportedVolume v = extract_layer(*level_, ExportLayer::visibility);
  EXPECT_EQ(v.nx, 21);
  EXPECT_EQ(v.ny, 21);
  EXPECT_EQ(v.nz, 10);
  EXPECT_DOUBLE_EQ(v.origin[0], hf_.x_of(0));
  EXPECT_DOUBLE_EQ(v.origin[1], hf_.y_of(20));  // the southernmost row
  EXPECT_DOUBLE_EQ(v.spacing[1], hf_.spacing_m);
  // Sample (x index 3, y index 0, level 4) is post (3, 20) at level 4.
  EXPECT_EQ(v.values[static_cast<std::size_t>((4 * 21 + 0) * 21 + 3)], level_->voxel(3, 20, 4));
  const ExportedVolume h = extract_layer(*level_, ExportLayer::height);
  EXPECT_EQ(h.nz, 1);
  EXPECT_EQ(h.values[static_cast<std::size_t>(20 * 21 + 5)], level_->post(5, 0));
  const ExportedVolume g = extract_layer(*level_, ExportLayer::gradient);
  EXPECT_EQ(g.components, 3);
  EXPECT_EQ(g.values.size(), 21u * 21u * 10u * 3u);
}

TEST_F(Export, MetaImageHeaderAndData) {
  const ExportedVolume v = extract_layer(*level_, ExportLayer::visibility);
  const std::string out = ::testing::TempDir() + "/export_" + std::to_string(getpid()) + ".mhd";
  ASSERT_TRUE(write_volume(out, v, ExportFormat::mhd).ok());
  std::ifstream in(out, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  EXPECT_NE(s.find("DimSize = 21 21 10\n"), std::string::npos);
  EXPECT_NE(s.find("ElementType = MET_FLOAT\n"), std::string::npos);
  EXPECT_NE(s.find("ElementDataFile = LOCAL\n"), std::string::npos);
  const std::size_t data = s.find("LOCAL\n") + 6;
  EXPECT_EQ(s.size() - data, v.values.size() * sizeof(float));
  float first;
  std::memcpy(&first, s.data() + data, sizeof first);
  EXPECT_EQ(first, v.values[0]);
  std::remove(out.c_str());
}

TEST_F(Export, VtkImageDataWithAppendedRawData) {
  const ExportedVolume v = extract_layer(*level_, ExportLayer::tff);
  const std::string out = ::testing::TempDir() + "/export_" + std::to_string(getpid()) + ".vti";
  ASSERT_TRUE(write_volume(out, v, ExportFormat::vti).ok());
  std::ifstream in(out, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  EXPECT_NE(s.find("WholeExtent=\"0 20 0 20 0 9\""), std::string::npos);
  EXPECT_NE(s.find("NumberOfComponents=\"3\""), std::string::npos);
  const std::size_t mark = s.find("   _") + 4;
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, s.data() + mark, sizeof bytes);
  EXPECT_EQ(bytes, v.values.size() * sizeof(float));
  std::remove(out.c_str());
}

TEST(ExportOptions, ParseNamesAndRejectsUnknown) {
  EXPECT_TRUE(parse_export_layer("tff").ok());
  EXPECT_FALSE(parse_export_layer("fp").ok());
  EXPECT_TRUE(parse_export_format("vti").ok());
  EXPECT_NE(parse_export_format("nrrd").status().message().find("mhd, vti"), std::string::npos);
}

}  // namespace
}  // namespace visvol::storage
