#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "../fields/terrains.hpp"
#include "fields/pyramid.hpp"
#include "fields/sampler.hpp"
#include "io/atomic_file.hpp"
#include "pack_bytes.hpp"
#include "storage/crc32c.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "storage/pack_writer.hpp"
#include "tests/support/local_row_exchange.hpp"

namespace visvol::storage {
namespace {

using namespace visvol::fields::testing;
using fields::Heightfield;
using testing::read_bytes;
using testing::without_build_time;

std::string temp_path(const std::string& stem) {
  return ::testing::TempDir() + "/" + stem + "_" + std::to_string(::getpid()) + ".vvp";
}

void write_file(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

PackBuildParams small_params(VisibilityEncoding enc = VisibilityEncoding::uint16) {
  PackBuildParams p;
  p.field.nz = 24;
  p.field.ceiling_m = 100;
  p.field.range_posts = 10;
  p.lod_levels = 2;
  p.encoding = enc;
  p.tff.band_offset_m = 60;
  p.tff.band_levels = 8;
  p.crs_name = "test frame";
  return p;
}

// A pack built once per suite (building takes a moment).
class PackFile : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    terrain_ = new Heightfield(fractal(37, 5));
    path_ = new std::string(temp_path("suite"));
    ASSERT_TRUE(build_pack(*terrain_, small_params(), R"({"path":"fractal"})", *path_).ok());
  }
  static void TearDownTestSuite() {
    std::remove(path_->c_str());
    delete terrain_;
    delete path_;
  }
  static Heightfield* terrain_;
  static std::string* path_;
};
Heightfield* PackFile::terrain_ = nullptr;
std::string* PackFile::path_ = nullptr;

TEST(Crc32c, KnownVectorAndContinuation) {
  EXPECT_EQ(crc32c("123456789", 9), 0xE3069283u);
  EXPECT_EQ(crc32c("6789", 4, crc32c("12345", 5)), 0xE3069283u);
  EXPECT_EQ(crc32c("", 0), 0u);
}

TEST_F(PackFile, RoundTripMatchesTheInMemoryBuild) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok()) << pack.status().message();
  ASSERT_EQ((*pack)->level_count(), 2);
  const PackBuildParams p = small_params();
  Result<std::vector<fields::LodLevel>> dense = fields::build_pyramid_dense(*terrain_, p.field, 2);
  ASSERT_TRUE(dense.ok());
  for (int l = 0; l < 2; ++l) {
    Result<PackLevel> level = PackLevel::open(*pack, l);
    ASSERT_TRUE(level.ok()) << level.status().message();
    const fields::LodLevel& want = (*dense)[static_cast<std::size_t>(l)];
    const fields::VolumeGeometry& g = level->geometry();
    EXPECT_EQ(g.nx, want.field.geometry.nx);
    EXPECT_EQ(g.ny, want.field.geometry.ny);
    EXPECT_DOUBLE_EQ(g.spacing_m, want.field.geometry.spacing_m);
    EXPECT_DOUBLE_EQ(g.origin_x, want.field.geometry.origin_x);
    EXPECT_DOUBLE_EQ(g.z0_m, want.field.geometry.z0_m);
    EXPECT_DOUBLE_EQ(g.dz_m, want.field.geometry.dz_m);
    const std::vector<float> area = fields::area_factor(want.terrain);
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        ASSERT_EQ(level->post(i, j), want.terrain.at(i, j));
        ASSERT_EQ(level->area(i, j), area[static_cast<std::size_t>(j * g.nx + i)]);
        for (int k = 0; k < g.nz; ++k) {
          ASSERT_NEAR(level->voxel(i, j, k), want.field.at(i, j, k), 0.5f / 65535.0f);
        }
      }
    }
  }
}

TEST_F(PackFile, TerrainForceBandMatchesDirectComputation) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  Result<PackLevel> level = PackLevel::open(*pack, 0);
  ASSERT_TRUE(level.ok());
  const fields::TffParams tp = level->tff_params();
  std::vector<fields::TffSample> band(static_cast<std::size_t>(terrain_->ny) *
                                      static_cast<std::size_t>(tp.band_levels) *
                                      static_cast<std::size_t>(terrain_->nx));
  fields::terrain_force_rows(*terrain_, tp, 0, terrain_->ny, band.data(), nullptr);
  for (int j = 0; j < terrain_->ny; ++j)
    for (int b = 0; b < tp.band_levels; ++b)
      for (int i = 0; i < terrain_->nx; ++i) {
        const fields::TffSample& want = band[static_cast<std::size_t>((j * tp.band_levels + b) * terrain_->nx + i)];
        const fields::TffSample got = level->tff(i, j, b);
        ASSERT_NEAR(got.dx_m, want.dx_m, 0.006);  // stored in centimetres
        ASSERT_NEAR(got.dz_m, want.dz_m, 0.006);
        ASSERT_NEAR(got.signed_distance_m, want.signed_distance_m, 0.006);
      }
}

TEST_F(PackFile, SamplerReadsThePackLikeTheDenseField) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  Result<PackLevel> level = PackLevel::open(*pack, 0);
  ASSERT_TRUE(level.ok());
  Result<std::vector<fields::LodLevel>> dense = fields::build_pyramid_dense(*terrain_, small_params().field, 1);
  ASSERT_TRUE(dense.ok());
  const fields::FieldSampler<PackLevel> from_pack(*level);
  const fields::FieldSampler<fields::DenseLevelView> from_memory(
      fields::DenseLevelView((*dense)[0].terrain, (*dense)[0].field));
  for (double f : {0.13, 0.5, 0.77}) {
    const double x = terrain_->x_of(f * 36), y = terrain_->y_of((1 - f) * 36);
    const double z = terrain_->at(18, 18) + 40 * f;
    EXPECT_NEAR(from_pack.visibility(x, y, z), from_memory.visibility(x, y, z), 1e-4);
    EXPECT_NEAR(from_pack.height(x, y), from_memory.height(x, y), 1e-6);
    EXPECT_LT((from_pack.gradient(x, y, z) - from_memory.gradient(x, y, z)).norm(), 1e-5);
  }
}

TEST_F(PackFile, MetadataRecordsGeoreferenceBuildAndSource) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  EXPECT_EQ((*pack)->metadata().crs_name, "test frame");
  EXPECT_EQ((*pack)->metadata().source_path, "fractal");
  const nlohmann::json j = nlohmann::json::parse((*pack)->metadata().json);
  EXPECT_EQ(j["build"]["nz"], 24);
  EXPECT_EQ(j["build"]["range_posts"], 10);
  EXPECT_EQ(j["build"]["visibility_encoding"], "uint16");
  EXPECT_DOUBLE_EQ(j["geotransform"][0].get<double>(), terrain_->origin_x - 0.5 * terrain_->spacing_m);
  EXPECT_EQ(j["levels"].size(), 2u);
  EXPECT_TRUE(j["tool"].get<std::string>().rfind("visvol ", 0) == 0);
}

TEST_F(PackFile, VerifyPassesAndNamesACorruptTile) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  EXPECT_TRUE((*pack)->verify().ok());
  const TileEntry t = (*pack)->tile(1, Layer::visibility, 1, 0);
  const std::string bad = temp_path("corrupt_tile");
  std::vector<char> bytes = read_bytes(*path_);
  bytes[t.offset + 100] ^= 0x40;
  write_file(bad, bytes);
  Result<std::shared_ptr<const Pack>> corrupted = Pack::open(bad);
  ASSERT_TRUE(corrupted.ok());  // structure is intact; the tile is not
  const Status st = (*corrupted)->verify();
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.code(), Errc::corrupt);
  EXPECT_NE(st.message().find("visibility tile (1, 0) of level 1"), std::string::npos) << st.message();
  const Result<PackLevel> level = PackLevel::open(*corrupted, 1);
  ASSERT_FALSE(level.ok());
  EXPECT_NE(level.status().message().find("visibility tile (1, 0)"), std::string::npos);
  EXPECT_TRUE(PackLevel::open(*corrupted, 0).ok());  // the other level is fine
  std::remove(bad.c_str());
}

TEST_F(PackFile, TruncationHeaderAndTableDamageAreNamed) {
  const std::vector<char> good = read_bytes(*path_);
  const std::string bad = temp_path("damaged");
  struct Case {
    const char* what;
    std::function<void(std::vector<char>&)> damage;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"truncated", [](std::vector<char>& b) { b.erase(b.end() - 5000, b.end()); }, "truncated"},
      {"tiny", [](std::vector<char>& b) { b.erase(b.begin() + 100, b.end()); }, "smaller than a pack header"},
      {"magic", [](std::vector<char>& b) { b[0] = 'X'; }, "not a visvol pack"},
      {"header", [](std::vector<char>& b) { b[40] ^= 1; }, "header checksum"},
      {"metadata", [](std::vector<char>& b) { b[b.size() - 3] ^= 1; }, "table or metadata checksum"},
      // damage to the level table reads as damage, not as a forged grid
      {"level table",
       [](std::vector<char>& b) {
         PackHeader h;
         std::memcpy(&h, b.data(), sizeof h);
         b[h.level_table_offset + offsetof(LevelEntry, nx) + 1] ^= 0x40;
       },
       "table or metadata checksum"},
      {"grown", [](std::vector<char>& b) { b.push_back(0); }, "the header says"},
  };
  for (const Case& c : cases) {
    std::vector<char> bytes = good;
    c.damage(bytes);
    write_file(bad, bytes);
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(bad);
    ASSERT_FALSE(pack.ok()) << c.what;
    EXPECT_NE(pack.status().message().find(c.expect), std::string::npos) << c.what << ": " << pack.status().message();
  }
  std::remove(bad.c_str());
}

// Rewrites fields of the header (and the tables) and fixes the checksums, so
// the structural checks, not the checksums, must catch the damage.
std::vector<char> forge(const std::vector<char>& good,
                        const std::function<void(PackHeader&, std::vector<char>&)>& edit) {
  std::vector<char> b = good;
  PackHeader h;
  std::memcpy(&h, b.data(), sizeof h);
  edit(h, b);
  if (h.level_table_offset < b.size()) {
    h.tables_crc32c = crc32c(b.data() + h.level_table_offset, b.size() - h.level_table_offset);
  }
  h.header_crc32c = crc32c(&h, offsetof(PackHeader, header_crc32c));
  std::memcpy(b.data(), &h, sizeof h);
  return b;
}

TEST_F(PackFile, ForgedStructuresAreRefusedByName) {
  const std::vector<char> good = read_bytes(*path_);
  const std::string bad = temp_path("forged");
  auto tile_at = [&](std::vector<char>& b, const PackHeader& h, std::uint64_t n) {
    return reinterpret_cast<TileEntry*>(b.data() + h.tile_table_offset + n * sizeof(TileEntry));
  };
  struct Case {
    const char* what;
    std::function<void(PackHeader&, std::vector<char>&)> edit;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"version", [](PackHeader& h, std::vector<char>&) { h.version = 99; }, "pack version 99"},
      {"levels", [](PackHeader& h, std::vector<char>&) { h.level_count = 0; }, "level_count 0"},
      {"tile count", [](PackHeader& h, std::vector<char>&) { h.tile_count = 1ull << 40; }, "tile table"},
      {"band", [](PackHeader& h, std::vector<char>&) { h.band_levels = 1000; }, "terrain force band"},
      {"encoding", [](PackHeader& h, std::vector<char>&) { h.visibility_encoding = 7; }, "visibility_encoding 7"},
      {"misaligned tile", [&](PackHeader& h, std::vector<char>& b) { tile_at(b, h, 3)->offset += 8; }, "is invalid"},
      {"tile beyond tables",
       [&](PackHeader& h, std::vector<char>& b) { tile_at(b, h, 5)->offset = h.level_table_offset; }, "is invalid"},
      {"shared bytes",
       [&](PackHeader& h, std::vector<char>& b) { tile_at(b, h, 6)->offset = tile_at(b, h, 5)->offset; },
       "overlaps the tile before it"},
      {"swapped identity", [&](PackHeader& h, std::vector<char>& b) { tile_at(b, h, 2)->tx = 9; }, "tile entry 2"},
      {"metadata beyond the cap",
       [](PackHeader& h, std::vector<char>& b) {
         b.resize(static_cast<std::size_t>(h.metadata_offset + kMaxMetadataBytes + 1), ' ');
         h.metadata_bytes = kMaxMetadataBytes + 1;
         h.file_bytes = b.size();
       },
       "a pack may hold"},
      {"level grid",
       [&](PackHeader& h, std::vector<char>& b) {
         reinterpret_cast<LevelEntry*>(b.data() + h.level_table_offset)->nz = 1000;
       },
       "level 0: grid"},
  };
  for (const Case& c : cases) {
    write_file(bad, forge(good, c.edit));
    const Result<std::shared_ptr<const Pack>> pack = Pack::open(bad);
    ASSERT_FALSE(pack.ok()) << c.what;
    EXPECT_NE(pack.status().message().find(c.expect), std::string::npos) << c.what << ": " << pack.status().message();
  }
  std::remove(bad.c_str());
}

// The console's terrain catalogue inspects packs that operators may be
// copying in: nothing of an inspected pack is mapped, so a file cut short
// under it is an error, never SIGBUS.
TEST_F(PackFile, AnInspectedPackIsNotMappedAndReadsAsAMappedOne) {
  Result<std::shared_ptr<const Pack>> mapped = Pack::open(*path_);
  Result<std::shared_ptr<const Pack>> inspected = Pack::open(*path_, PackAccess::inspect);
  ASSERT_TRUE(mapped.ok() && inspected.ok()) << inspected.status().message();
  const Pack& m = **mapped;
  const Pack& i = **inspected;
  EXPECT_NE(m.mapping(), nullptr);
  EXPECT_EQ(i.mapping(), nullptr);
  EXPECT_EQ(i.metadata().json, m.metadata().json);
  ASSERT_EQ(i.level_count(), m.level_count());
  ASSERT_EQ(i.tile_count(), m.tile_count());
  EXPECT_EQ(std::memcmp(&i.level(1), &m.level(1), sizeof(LevelEntry)), 0);
  EXPECT_EQ(std::memcmp(&i.tile_entry(i.tile_count() - 1), &m.tile_entry(m.tile_count() - 1), sizeof(TileEntry)), 0);
  // its tiles are read, then checked
  Result<InputFile> file = InputFile::open(*path_);
  ASSERT_TRUE(file.ok());
  std::vector<std::uint8_t> bytes;
  for (std::uint64_t n = 0; n < i.tile_count(); ++n) {
    const TileEntry& t = i.tile_entry(n);
    bytes.resize(t.bytes);
    ASSERT_TRUE(file->read_at(bytes.data(), bytes.size(), t.offset).ok());
    ASSERT_TRUE(i.verify_tile_bytes(t, bytes.data()).ok()) << Pack::describe(t);
  }
  // verified, with pread, from the file it opened; read_tile copies and checks
  EXPECT_TRUE(i.verify().ok());
  const TileEntry& first = i.tile_entry(0);
  std::vector<std::uint8_t> copy(first.bytes);
  ASSERT_TRUE(i.read_tile(first, copy.data()).ok());
  EXPECT_EQ(std::memcmp(copy.data(), m.tile_data(first), first.bytes), 0);
  // and never read through a mapping it does not have
  const Result<PackLevel> level = PackLevel::open(*inspected, 0);
  ASSERT_FALSE(level.ok());
  EXPECT_EQ(level.status().code(), Errc::state);
  EXPECT_NE(level.status().message().find("not mapped"), std::string::npos) << level.status().message();
}

TEST_F(PackFile, AnInspectedPackChecksItsHeightsAsRead) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  const TileEntry t = (*pack)->tile(1, Layer::height, 0, 0);
  std::vector<char> bytes = read_bytes(*path_);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(bytes.data() + t.offset + 4 * sizeof(float), &nan, sizeof nan);
  const std::string bad = temp_path("nan_height");
  write_file(bad, bytes);
  for (PackAccess access : {PackAccess::mapped, PackAccess::inspect}) {
    const Result<std::shared_ptr<const Pack>> opened = Pack::open(bad, access);
    ASSERT_FALSE(opened.ok());
    EXPECT_NE(opened.status().message().find("height tile (0, 0) of level 1"), std::string::npos)
        << opened.status().message();
  }
  std::remove(bad.c_str());
}

// A pack's footprint from its header and level table: the tables from the
// level table to the end of the file, and every level's heights; a file that
// is no pack is refused as open() refuses it.
TEST_F(PackFile, AFootprintIsItsTablesAndHeights) {
  Result<std::shared_ptr<const Pack>> pack = Pack::open(*path_);
  ASSERT_TRUE(pack.ok());
  const Result<PackFootprint> size = Pack::footprint(*path_);
  ASSERT_TRUE(size.ok()) << size.status().message();
  EXPECT_EQ(size->table_bytes, (*pack)->file_bytes() - (*pack)->header().level_table_offset);
  std::uint64_t heights = 0;
  for (int l = 0; l < (*pack)->level_count(); ++l) {
    heights += std::uint64_t{4} * static_cast<std::uint64_t>((*pack)->level(l).nx) *
               static_cast<std::uint64_t>((*pack)->level(l).ny);
  }
  EXPECT_EQ(size->height_bytes, heights);
  std::vector<char> bytes = read_bytes(*path_);
  bytes[0] ^= 1;  // the magic
  const std::string bad = temp_path("footprint_bad");
  write_file(bad, bytes);
  const Result<PackFootprint> refused = Pack::footprint(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("not a visvol pack"), std::string::npos) << refused.status().message();
  std::remove(bad.c_str());
}

// The header and tables are the pack's own copy: a file truncated under an
// open pack (a copy over it) faults none of them (before, the tables at the
// end of the file were read through the mapping).
TEST_F(PackFile, TheTablesOutliveTheFileBeingCutShort) {
  const std::string copy = temp_path("cut_short");
  write_file(copy, read_bytes(*path_));
  Result<std::shared_ptr<const Pack>> pack = Pack::open(copy);
  ASSERT_TRUE(pack.ok());
  const std::uint64_t count = (*pack)->tile_count();
  const TileEntry last = (*pack)->tile_entry(count - 1);
  ASSERT_EQ(::truncate(copy.c_str(), 0), 0);
  EXPECT_EQ(std::memcmp(&(*pack)->tile_entry(count - 1), &last, sizeof last), 0);
  EXPECT_EQ((*pack)->header().tile_count, count);
  EXPECT_GE((*pack)->level(0).nx, 2);
  EXPECT_NE((*pack)->metadata().json.find("fractal"), std::string::npos);
  std::remove(copy.c_str());
}

TEST(PackWriter, AbandonedWriteLeavesTheOldPackAndNoTemporary) {
  const Heightfield hf = fractal(24, 3);
  const std::string path = temp_path("abandoned");
  ASSERT_TRUE(build_pack(hf, small_params(), "", path).ok());
  const std::vector<char> before = read_bytes(path);
  {
    PackLayout layout;
    LevelEntry e{};
    e.nx = 20;
    e.ny = 20;
    e.nz = 8;
    e.spacing_m = 30;
    e.dz_m = 5;
    layout.levels.push_back(e);
    Result<std::unique_ptr<PackWriter>> w = PackWriter::create(path, layout);
    ASSERT_TRUE(w.ok());
    std::vector<char> tile((*w)->payload_bytes(0, Layer::height), 0);
    ASSERT_TRUE((*w)->write_tile(0, Layer::height, 0, 0, tile.data(), tile.size()).ok());
    // finish() never called: the writer is dropped mid-way.
  }
  EXPECT_EQ(read_bytes(path), before);
  EXPECT_NE(access((temporary_prefix(path) + std::to_string(getpid())).c_str(), F_OK), 0);
  std::remove(path.c_str());
}

TEST(PackWriter, KilledBuildNeverLeavesATornPack) {
  const Heightfield hf = fractal(48, 4);
  const std::string path = temp_path("killed");
  ASSERT_TRUE(build_pack(hf, small_params(), "", path).ok());
  const std::vector<char> before = read_bytes(path);
  const pid_t pid = fork();
  if (pid == 0) {
    PackBuildParams p = small_params();
    p.field.range_posts = 40;  // slow enough to be killed mid-build
    p.field.nz = 200;
    (void)build_pack(hf, p, "", path);
    _exit(0);
  }
  usleep(150 * 1000);
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  // Either the old pack, or (had the child finished) a complete new one.
  const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  ASSERT_TRUE(pack.ok()) << pack.status().message();
  EXPECT_TRUE((*pack)->verify().ok());
  if (WIFSIGNALED(status)) {
    EXPECT_EQ(read_bytes(path), before);
  }
  std::remove(path.c_str());
  std::remove((temporary_prefix(path) + std::to_string(pid)).c_str());  // the killed build's stray temporary
}

TEST(PackWriter, RefusesMissingTilesAndWrongSizes) {
  PackLayout layout;
  LevelEntry e{};
  e.nx = 20;
  e.ny = 20;
  e.nz = 8;
  e.spacing_m = 30;
  e.dz_m = 5;
  layout.levels.push_back(e);
  const std::string path = temp_path("incomplete");
  Result<std::unique_ptr<PackWriter>> w = PackWriter::create(path, layout);
  ASSERT_TRUE(w.ok());
  std::vector<char> tile(16);
  EXPECT_FALSE((*w)->write_tile(0, Layer::height, 0, 0, tile.data(), tile.size()).ok());
  EXPECT_FALSE((*w)->write_tile(0, Layer::height, 5, 0, tile.data(), tile.size()).ok());
  const Status st = (*w)->finish("{}");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("was never written"), std::string::npos);
  EXPECT_NE(access(path.c_str(), F_OK), 0);
}

TEST(PackWriter, RejectsInvalidLayouts) {
  PackLayout layout;
  EXPECT_FALSE(validate(layout).ok());  // no levels
  LevelEntry e{};
  e.nx = 1;
  e.ny = 20;
  e.nz = 8;
  e.spacing_m = 30;
  e.dz_m = 5;
  layout.levels.push_back(e);
  EXPECT_FALSE(validate(layout).ok());
}

TEST(PackBuild, Float32EncodingIsExact) {
  const Heightfield hf = fractal(24, 6);
  const std::string path = temp_path("float32");
  const PackBuildParams p = small_params(VisibilityEncoding::float32);
  ASSERT_TRUE(build_pack(hf, p, "", path).ok());
  Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  ASSERT_TRUE(pack.ok());
  Result<PackLevel> level = PackLevel::open(*pack, 0);
  ASSERT_TRUE(level.ok());
  Result<fields::DenseVolume> dense = fields::build_visibility_dense(hf, [&] {
    fields::FieldParams f = p.field;
    const fields::VolumeGeometry g = fields::volume_geometry(hf, f);
    f.vertical = fields::VerticalGrid{g.z0_m, g.dz_m};
    return f;
  }());
  ASSERT_TRUE(dense.ok());
  for (int k = 0; k < 24; ++k) ASSERT_EQ(level->voxel(7, 9, k), dense->at(7, 9, k));
  std::remove(path.c_str());
}

TEST(PackBuild, RefusesBadParametersBeforeWriting) {
  const Heightfield hf = fractal(24, 6);
  const std::string path = temp_path("refused");
  PackBuildParams p = small_params();
  p.tff.band_offset_m = 1000;
  EXPECT_FALSE(build_pack(hf, p, "", path).ok());
  p = small_params();
  p.lod_levels = 9;
  EXPECT_FALSE(build_pack(hf, p, "", path).ok());
  EXPECT_FALSE(build_pack(hf, small_params(), "{not json", path).ok());
  EXPECT_NE(access(path.c_str(), F_OK), 0);
}

// Another process's writes into the writer's temporary: its own descriptor,
// pwrite at the placement's offsets, the checksums handed over at the end.
class ForeignSink final : public TileSink {
 public:
  ForeignSink(const TilePlacement& placement, const std::string& path)
      : placement_(placement), fd_(::open(path.c_str(), O_WRONLY | O_NOFOLLOW | O_CLOEXEC)) {}
  ~ForeignSink() override { ::close(fd_); }
  Status write_tile(int level, Layer layer, int tx, int ty, const void* payload, std::size_t bytes) override {
    const Result<TilePlacement::Stored> stored =
        placement_.store(level, layer, tx, ty, payload, bytes, [&](const void* data, std::size_t n, std::uint64_t at) {
          return ::pwrite(fd_, data, n, static_cast<off_t>(at)) == static_cast<ssize_t>(n)
                     ? Status::ok_status()
                     : Status(Errc::output, "pwrite failed");
        });
    if (!stored.ok()) return stored.status();
    written.emplace_back(stored->index, stored->crc32c);
    return Status::ok_status();
  }
  std::vector<std::pair<std::size_t, std::uint32_t>> written;

 private:
  const TilePlacement& placement_;
  int fd_;
};

// Every share of a split build, share 0 through `writer`, the others as other
// processes would write: split by rows one after the other, split by
// observers at once (threads here, processes under MPI), each computing its
// band's hulls only and sending the sums over other bands' rows to their
// owners through one mailbox. Returns the rows sent.
std::uint64_t build_shares(const PackPlan& plan, const PackBuildParams& p, int count, bool by_observers,
                           PackWriter& writer) {
  test::LocalRowMail mail(count);
  std::vector<std::unique_ptr<ForeignSink>> others;
  for (int index = 1; index < count; ++index)
    others.push_back(std::make_unique<ForeignSink>(writer.placement(), writer.write_path()));
  std::vector<Status> built(static_cast<std::size_t>(count), Status::ok_status());
  auto share = [&](int index) {
    TileSink& sink = index == 0 ? static_cast<TileSink&>(writer) : *others[static_cast<std::size_t>(index - 1)];
    built[static_cast<std::size_t>(index)] =
        build_pack_share(plan, p, BuildShare{index, count, by_observers ? &mail.share(index) : nullptr}, sink);
  };
  std::vector<std::thread> threads;
  for (int index = 0; index < count; ++index) {
    if (by_observers) {
      threads.emplace_back(share, index);
    } else {
      share(index);
    }
  }
  for (std::thread& t : threads) t.join();
  for (const Status& st : built) EXPECT_TRUE(st.ok()) << st.message();
  for (const auto& other : others)
    for (const auto& [tile, crc] : other->written) EXPECT_TRUE(writer.add_written_tile(tile, crc).ok());
  return mail.rows_sent();
}

TEST(PackBuild, ABuildSplitIntoSharesIsTheWholeBuildByteForByte) {
  // 70 rows: 5 brick rows and 2 height-tile rows at level 0, 3 and 1 at
  // level 1: shares with none, one or several rows of each.
  const Heightfield hf = fractal(70, 8);
  PackBuildParams p = small_params();
  p.field.range_posts = 12;  // a share's rows need observers of its neighbours' rows
  const std::string whole = temp_path("whole"), split = temp_path("split");
  ASSERT_TRUE(build_pack(hf, p, R"({"path":"fractal"})", whole).ok());
  for (const bool by_observers : {false, true}) {
    for (const int count : {2, 3, 7}) {
      Result<PackPlan> plan = plan_pack(hf, p);
      ASSERT_TRUE(plan.ok()) << plan.status().message();
      Result<std::unique_ptr<PackWriter>> w = PackWriter::create_shared(split, plan->layout);
      ASSERT_TRUE(w.ok());
      const std::uint64_t rows_sent = build_shares(*plan, p, count, by_observers, **w);
      EXPECT_EQ(rows_sent > 0, by_observers);
      Result<std::string> meta = pack_metadata(hf, p, R"({"path":"fractal"})", *plan);
      ASSERT_TRUE(meta.ok());
      ASSERT_TRUE((*w)->finish(*meta).ok());
      EXPECT_TRUE(without_build_time(split) == without_build_time(whole))
          << count << " shares, split by " << (by_observers ? "observers" : "rows");
      const Result<std::shared_ptr<const Pack>> pack = Pack::open(split);
      ASSERT_TRUE(pack.ok());
      EXPECT_TRUE((*pack)->verify().ok());
    }
  }
  std::remove(whole.c_str());
  std::remove(split.c_str());
}

TEST(PackBuild, AShareLeftOutIsNamedAndNothingIsWritten) {
  const Heightfield hf = fractal(40, 2);
  const PackBuildParams p = small_params();
  const std::string path = temp_path("share_left_out");
  Result<PackPlan> plan = plan_pack(hf, p);
  ASSERT_TRUE(plan.ok());
  Result<std::unique_ptr<PackWriter>> w = PackWriter::create(path, plan->layout);
  ASSERT_TRUE(w.ok());
  ASSERT_TRUE(build_pack_share(*plan, p, BuildShare{0, 2}, **w).ok());
  const Status st = (*w)->finish("{}");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("was never written"), std::string::npos) << st.message();
  EXPECT_NE(access(path.c_str(), F_OK), 0);
  Result<std::unique_ptr<PackWriter>> fresh = PackWriter::create(path, plan->layout);
  ASSERT_TRUE(fresh.ok());
  EXPECT_FALSE(build_pack_share(*plan, p, BuildShare{2, 2}, **fresh).ok());
  EXPECT_FALSE(build_pack_share(*plan, p, BuildShare{0, 0}, **fresh).ok());
  const std::size_t tiles = (*fresh)->placement().tiles.size();
  const Status st2 = (*fresh)->add_written_tile(tiles, 0);
  EXPECT_EQ(st2.code(), Errc::invalid_argument);
  EXPECT_NE(st2.message().find("no tile " + std::to_string(tiles)), std::string::npos) << st2.message();
  EXPECT_TRUE((*fresh)->add_written_tile(tiles - 1, 0).ok());
}

TEST(PackBuild, SharesCoverEveryTileRowOnce) {
  for (const int rows : {0, 1, 5, 64, 1251}) {
    for (const int count : {1, 2, 3, 7, 64}) {
      int next = 0;
      for (int index = 0; index < count; ++index) {
        const TileRows r = share_tile_rows(rows, BuildShare{index, count});
        EXPECT_EQ(r.first, next);
        EXPECT_LE(r.end - r.first, rows / count + 1);
        next = r.end;
      }
      EXPECT_EQ(next, rows);
    }
  }
}

TEST(PackReader, MissingFileNamesIt) {
  const Result<std::shared_ptr<const Pack>> pack = Pack::open("/nonexistent/x.vvp");
  ASSERT_FALSE(pack.ok());
  EXPECT_EQ(pack.status().code(), Errc::io);
  EXPECT_NE(pack.status().message().find("/nonexistent/x.vvp"), std::string::npos);
}

}  // namespace
}  // namespace visvol::storage
