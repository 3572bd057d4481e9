// Reading a pack through checked copies (TileCopy, CachedLevel): the values
// are exactly the mapped level's, whatever the cache's size; a pack cut short
// or rewritten under a reader is counted and named, never a fault.
#include "storage/cached_level.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "../fields/terrains.hpp"
#include "fields/sampler.hpp"
#include "storage/pack_build.hpp"

namespace visvol::storage {
namespace {

class CachedLevelTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fields::Heightfield hf = fields::testing::fractal(97, 7);  // 7 x 7 bricks
    PackBuildParams p;
    p.field.nz = 24;
    p.field.ceiling_m = 150;
    p.field.range_posts = 6;
    p.lod_levels = 2;
    p.tff.band_offset_m = 40;
    p.tff.band_levels = 6;
    path_ = new std::string(::testing::TempDir() + "/cached_" + std::to_string(::getpid()) + ".vvp");
    ASSERT_TRUE(build_pack(hf, p, "", *path_).ok());
  }
  static void TearDownTestSuite() {
    std::remove(path_->c_str());
    delete path_;
  }
  static std::string copy_of_pack(const std::string& name) {
    const std::string c = ::testing::TempDir() + "/cached_" + name + "_" + std::to_string(::getpid()) + ".vvp";
    std::filesystem::copy_file(*path_, c, std::filesystem::copy_options::overwrite_existing);
    return c;
  }
  static std::string* path_;
};
std::string* CachedLevelTest::path_ = nullptr;

void expect_same(const fields::TffSample& a, const fields::TffSample& b) {
  EXPECT_EQ(a.dx_m, b.dx_m);
  EXPECT_EQ(a.dy_m, b.dy_m);
  EXPECT_EQ(a.dz_m, b.dz_m);
  EXPECT_EQ(a.signed_distance_m, b.signed_distance_m);
}

TEST_F(CachedLevelTest, ATileCopyHoldsTheCheckedBytesOfTheTile) {
  auto pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  const TileEntry& t = (*pack)->tile(0, Layer::visibility, 3, 2);
  Result<TileCopy> c = TileCopy::read(**pack, t);
  ASSERT_TRUE(c.ok()) << c.status().message();
  ASSERT_EQ(c->bytes(), t.bytes);
  EXPECT_EQ(std::memcmp(c->data(), (*pack)->tile_data(t), t.bytes), 0);
  const TileCopy moved = std::move(*c);  // the pages move with it
  EXPECT_EQ(moved.bytes(), t.bytes);
  EXPECT_EQ(std::memcmp(moved.data(), (*pack)->tile_data(t), t.bytes), 0);
  EXPECT_TRUE(TileCopy().empty());
}

TEST_F(CachedLevelTest, ReadsExactlyWhatTheMappedLevelReadsWhateverItsCache) {
  auto pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  for (int level = 0; level < (*pack)->level_count(); ++level) {
    const Result<PackLevel> mapped = PackLevel::open(*pack, level);
    ASSERT_TRUE(mapped.ok());
    for (const int bricks : {1, 3, 64}) {
      Result<CachedLevel> cached = CachedLevel::open(*pack, level, bricks);
      ASSERT_TRUE(cached.ok()) << cached.status().message();
      const fields::VolumeGeometry g = mapped->geometry();
      std::mt19937 rng(static_cast<unsigned>(7 * level + bricks));
      for (int n = 0; n < 4000; ++n) {  // scattered reads: bricks come and go
        const int i = std::uniform_int_distribution<int>(0, g.nx - 1)(rng);
        const int j = std::uniform_int_distribution<int>(0, g.ny - 1)(rng);
        const int k = std::uniform_int_distribution<int>(0, g.nz - 1)(rng);
        ASSERT_EQ(cached->post(i, j), mapped->post(i, j));
        ASSERT_EQ(cached->voxel(i, j, k), mapped->voxel(i, j, k)) << i << " " << j << " " << k;
        expect_same(cached->tff(i, j, k % 6), mapped->tff(i, j, k % 6));
      }
      // the sampler over it (by reference) answers as over the mapped level
      const fields::FieldSampler<CachedLevelRef> a{CachedLevelRef(*cached)};
      const fields::FieldSampler<PackLevel> b(*mapped);
      for (int n = 0; n < 200; ++n) {
        const double x = g.origin_x + std::uniform_real_distribution<double>(0, (g.nx - 1) * g.spacing_m)(rng);
        const double y = g.origin_y - std::uniform_real_distribution<double>(0, (g.ny - 1) * g.spacing_m)(rng);
        const double z = b.height(x, y) + std::uniform_real_distribution<double>(-20, 120)(rng);
        ASSERT_EQ(a.visibility(x, y, z), b.visibility(x, y, z));
        ASSERT_EQ(a.gradient(x, y, z), b.gradient(x, y, z));
      }
      EXPECT_EQ(cached->read_failures(), 0u);
    }
  }
  EXPECT_FALSE(CachedLevel::open(*pack, 0, 0).ok());
  EXPECT_FALSE(CachedLevel::open(*pack, 5).ok());
  EXPECT_GT(CachedLevel::bytes(**pack, 0, 4), 0u);
  EXPECT_LT(CachedLevel::bytes(**pack, 0, 4), CachedLevel::bytes(**pack, 0, 40));
}

TEST_F(CachedLevelTest, APackCutShortOrRewrittenIsCountedAndNamedNeverAFault) {
  for (const bool rewrite : {false, true}) {
    const std::string copy = copy_of_pack(rewrite ? "rewritten" : "cut");
    auto pack = Pack::open(copy, PackAccess::inspect);  // no mapping at all
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    Result<CachedLevel> cached = CachedLevel::open(*pack, 0, 4);
    ASSERT_TRUE(cached.ok()) << cached.status().message();
    const float held = cached->voxel(5, 5, 3);  // brick (0, 0) read and held
    const float height = cached->post(90, 90);
    if (rewrite) {
      const std::uint64_t size = (*pack)->file_bytes();
      std::fstream f(copy, std::ios::binary | std::ios::in | std::ios::out);
      const std::string junk(static_cast<std::size_t>(size - 4096), '\x33');
      ASSERT_TRUE(f.seekp(4096).write(junk.data(), static_cast<std::streamsize>(junk.size())).flush());
    } else {
      std::filesystem::resize_file(copy, 4096);
    }
    EXPECT_EQ(cached->voxel(5, 5, 3), held);    // held: unchanged
    EXPECT_EQ(cached->post(90, 90), height);    // heights are copied whole at open
    EXPECT_EQ(cached->voxel(90, 90, 3), 0.0f);  // another brick: unreadable, zeros
    EXPECT_EQ(cached->tff(90, 90, 2).signed_distance_m, 0.0f);
    EXPECT_EQ(cached->read_failures(), 1u);
    EXPECT_EQ(cached->zero_reads(), 2u);
    EXPECT_EQ(cached->voxel(91, 91, 4), 0.0f);  // the same brick is not read again, but every zero is counted
    EXPECT_EQ(cached->read_failures(), 1u);
    EXPECT_EQ(cached->zero_reads(), 3u);
    EXPECT_EQ(cached->voxel(5, 5, 3), held);
    EXPECT_EQ(cached->zero_reads(), 3u);
    EXPECT_NE(cached->last_error().find("of level 0"), std::string::npos) << cached->last_error();
    EXPECT_NE(cached->last_error().find(rewrite ? "checksum" : "ended at byte"), std::string::npos)
        << cached->last_error();
    // a level opened now cannot copy its heights: refused, named
    const Result<CachedLevel> again = CachedLevel::open(*pack, 0);
    EXPECT_FALSE(again.ok());
    // nor can a tile be verified
    EXPECT_FALSE((*pack)->verify().ok());
    std::remove(copy.c_str());
  }
}

}  // namespace
}  // namespace visvol::storage
