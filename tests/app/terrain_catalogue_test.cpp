#include "app/terrain_catalogue.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <filesystem>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <thread>

#include "../fields/terrains.hpp"
#include "console_packs.hpp"
#include "storage/pack_build.hpp"
#include "storage/pack_reader.hpp"
#include "tests/storage/bare_pack.hpp"
#include "tests/support/scratch.hpp"

namespace visvol::app {
namespace {

using testing::small_pack_params;

std::string make_folder(const std::string& name) {
  const std::string dir = visvol::test::scratch_path("catalogue_" + name);
  std::string rm = "rm -rf '" + dir + "'";
  EXPECT_EQ(std::system(rm.c_str()), 0);
  EXPECT_EQ(mkdir(dir.c_str(), 0755), 0);
  return dir;
}

void build(const std::string& path, int seed) {
  ASSERT_TRUE(
      storage::build_pack(fields::testing::fractal(33, static_cast<unsigned>(seed)), small_pack_params(), "", path)
          .ok());
}

// One byte of the pack's first tile flipped (its checksum then fails).
void damage_a_tile(const std::string& path) {
  std::uint64_t offset = 0;
  {
    auto pack = storage::Pack::open(path);
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    offset = (*pack)->tile_entry(0).offset + 17;
  }
  const int fd = open(path.c_str(), O_RDWR);
  ASSERT_GE(fd, 0);
  unsigned char b = 0;
  ASSERT_EQ(pread(fd, &b, 1, static_cast<off_t>(offset)), 1);
  b = static_cast<unsigned char>(b ^ 0x5a);
  ASSERT_EQ(pwrite(fd, &b, 1, static_cast<off_t>(offset)), 1);
  close(fd);
}

std::optional<CatalogueEntry> find(const TerrainCatalogue& c, const std::string& id) {
  for (const CatalogueEntry& e : c.entries()) {
    if (e.id == id) return e;
  }
  return std::nullopt;
}

// Waits for what inotify reports to be verified: until `id`'s state is `state`
// (or it is gone, for nullopt), at most 60 s.
bool wait_for(const TerrainCatalogue& c, const std::string& id, std::optional<CatalogueState> state) {
  for (int i = 0; i < 600; ++i) {
    const std::optional<CatalogueEntry> e = find(c, id);
    if (!state && !e) return true;
    if (state && e && e->state == *state) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

TEST(TerrainCatalogue, VerifiesEveryPackInTheFolderAndRefusesADamagedOne) {
  const std::string dir = make_folder("start");
  build(dir + "/good.vvp", 3);
  build(dir + "/bad.vvp", 4);
  damage_a_tile(dir + "/bad.vvp");
  std::ofstream(dir + "/notes.txt") << "not a pack\n";
  std::ofstream(dir + "/.partial.vvp") << "a writer's temporary file\n";
  std::ofstream(dir + "/bad name.vvp") << "not a pack id\n";
  ASSERT_EQ(mkdir((dir + "/folder.vvp").c_str(), 0755), 0);

  auto c = TerrainCatalogue::start(dir, 1);
  ASSERT_TRUE(c.ok()) << c.status().message();
  ASSERT_TRUE((*c)->wait_idle(60.0));
  const std::vector<CatalogueEntry> all = (*c)->entries();
  ASSERT_EQ(all.size(), 4u) << "good, bad, 'bad name' and folder; not the text file nor the dot file";
  const std::optional<CatalogueEntry> good = find(**c, "good");
  ASSERT_TRUE(good);
  EXPECT_EQ(good->state, CatalogueState::verified) << good->reason;
  EXPECT_EQ(good->levels, 2);
  EXPECT_GT(good->post_spacing_m, 0.0);
  EXPECT_FALSE(good->bounds.empty());
  EXPECT_NE(good->build_json.find("range"), std::string::npos) << good->build_json;
  EXPECT_EQ((*c)->verified_path("good"), dir + "/good.vvp");

  const std::optional<CatalogueEntry> bad = find(**c, "bad");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->state, CatalogueState::refused);
  EXPECT_NE(bad->reason.find("checksum"), std::string::npos) << bad->reason;
  EXPECT_EQ((*c)->verified_path("bad"), "") << "never switched to";
  const std::optional<CatalogueEntry> spaced = find(**c, "bad name");
  ASSERT_TRUE(spaced);
  EXPECT_EQ(spaced->state, CatalogueState::refused);
  EXPECT_NE(spaced->reason.find("not a pack id"), std::string::npos) << spaced->reason;
  const std::optional<CatalogueEntry> folder = find(**c, "folder");
  ASSERT_TRUE(folder);
  EXPECT_NE(folder->reason.find("not a regular file"), std::string::npos) << folder->reason;
}

TEST(TerrainCatalogue, ALevelThePackLacksIsRefused) {
  const std::string dir = make_folder("level");
  build(dir + "/two.vvp", 5);
  auto c = TerrainCatalogue::start(dir, 2);  // the console runs on level 2; the pack has 0 and 1
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE((*c)->wait_idle(60.0));
  const std::optional<CatalogueEntry> e = find(**c, "two");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->state, CatalogueState::refused);
  EXPECT_NE(e->reason.find("level"), std::string::npos) << e->reason;
}

// A pack whose tables and heights exceed the console's budget is refused
// from its header and level table, before its tables are read (a 32768 x
// 32768 grid's 214 MB tile table took a console over its 256 MiB budget as
// it was verified); within the budget it verifies.
TEST(TerrainCatalogue, APackLargerThanTheBudgetIsRefusedBeforeItsTablesAreRead) {
  const std::string dir = make_folder("budget");
  build(dir + "/big.vvp", 6);
  Result<storage::PackFootprint> size = storage::Pack::footprint(dir + "/big.vvp");
  ASSERT_TRUE(size.ok()) << size.status().message();
  const std::uint64_t held = size->table_bytes + size->height_bytes;
  auto c = TerrainCatalogue::start(dir, 0, held - 1);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE((*c)->wait_idle(60.0));
  const std::optional<CatalogueEntry> e = find(**c, "big");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->state, CatalogueState::refused);
  EXPECT_NE(e->reason.find("memory budget (--budget-mib)"), std::string::npos) << e->reason;
  CatalogueEntry fits;
  fits.id = "big";
  verify_catalogue_entry(dir + "/big.vvp", 0, fits, nullptr, held);
  EXPECT_EQ(fits.state, CatalogueState::verified) << fits.reason;
}

TEST(TerrainCatalogue, APackWithNoPlanningBoundsIsRefused) {
  // built before bounds were recorded, and no wider than twice its range:
  // `visvol plan` and `check` refuse it, and so does the console
  const std::string dir = make_folder("bounds");
  storage::testing::write_bare_pack(dir + "/narrow.vvp", storage::testing::level_40x30(15),
                                    R"({"build": {"range_shape": "cube"}})");
  auto c = TerrainCatalogue::start(dir, 0);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE((*c)->wait_idle(60.0));
  const std::optional<CatalogueEntry> e = find(**c, "narrow");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->state, CatalogueState::refused);
  EXPECT_NE(e->reason.find("no planning bounds"), std::string::npos) << e->reason;
}

// A folder of thousands of files (a mistaken copy, or an attack on the
// console's monitor, which compared the lists entry by entry): the catalogue
// keeps kMaxPacks of them and counts the rest.
TEST(TerrainCatalogue, KeepsAtMostItsCapacityOfPacks) {
  const std::string dir = make_folder("many");
  const std::size_t files = TerrainCatalogue::kMaxPacks + 40;
  for (std::size_t k = 0; k < files; ++k) std::ofstream(dir + "/p" + std::to_string(1000 + k) + ".vvp") << "no pack";
  auto c = TerrainCatalogue::start(dir, 0);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE((*c)->wait_idle(60.0));
  const std::vector<CatalogueEntry> entries = (*c)->entries();
  EXPECT_EQ(entries.size(), TerrainCatalogue::kMaxPacks);
  EXPECT_GE((*c)->left_out(), 40u);
  for (const CatalogueEntry& e : entries) EXPECT_EQ(e.state, CatalogueState::refused) << e.id;
  EXPECT_TRUE(std::is_sorted(entries.begin(), entries.end(),
                             [](const CatalogueEntry& a, const CatalogueEntry& b) { return a.id < b.id; }));
  c->reset();
  std::filesystem::remove_all(dir);
}

// Packs copied in (written elsewhere, renamed in), replaced the same way and
// removed while the catalogue runs are seen; each change is verified anew.
TEST(TerrainCatalogue, SeesPacksAddedReplacedAndRemoved) {
  const std::string dir = make_folder("watch");
  const std::string staging = make_folder("staging");
  auto c = TerrainCatalogue::start(dir, 0);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE((*c)->wait_idle(10.0));
  EXPECT_TRUE((*c)->entries().empty());

  build(staging + "/site.vvp", 6);
  const std::uint64_t before = (*c)->version();
  ASSERT_EQ(std::rename((staging + "/site.vvp").c_str(), (dir + "/site.vvp").c_str()), 0);
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::verified)) << "the pack renamed in never came";
  EXPECT_GT((*c)->version(), before);

  // written in place under a dot name, then renamed over the first: refused (damaged)
  build(dir + "/.site.vvp.part", 7);
  damage_a_tile(dir + "/.site.vvp.part");
  ASSERT_EQ(std::rename((dir + "/.site.vvp.part").c_str(), (dir + "/site.vvp").c_str()), 0);
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::refused)) << "the damaged replacement was not refused";
  EXPECT_EQ((*c)->verified_path("site"), "");

  // a good one copied in place with its final name (cp): verified once closed
  build(staging + "/other.vvp", 8);
  {
    std::ifstream from(staging + "/other.vvp", std::ios::binary);
    std::ofstream to(dir + "/other.vvp", std::ios::binary);
    to << from.rdbuf();
  }
  std::remove((staging + "/other.vvp").c_str());
  ASSERT_TRUE(wait_for(**c, "other", CatalogueState::verified)) << "the pack written in place never came";

  ASSERT_EQ(std::remove((dir + "/site.vvp").c_str()), 0);
  ASSERT_TRUE(wait_for(**c, "site", std::nullopt)) << "the removed pack stayed";
  ASSERT_EQ(std::rename((dir + "/other.vvp").c_str(), (staging + "/other.vvp").c_str()), 0);
  ASSERT_TRUE(wait_for(**c, "other", std::nullopt)) << "the pack moved out stayed";
  std::remove((staging + "/other.vvp").c_str());
}

// The folder moved away under it (a deployment swapping folders): its packs
// are refused, and no longer switched to; removed, they go with it.
TEST(TerrainCatalogue, AFolderMovedOrRemovedTakesItsPacksWithIt) {
  const std::string dir = make_folder("moved");
  build(dir + "/site.vvp", 9);
  auto c = TerrainCatalogue::start(dir, 0);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::verified));
  ASSERT_EQ(std::system(("rm -rf '" + dir + ".old' && mv '" + dir + "' '" + dir + ".old'").c_str()), 0);
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::refused)) << "the moved folder's pack stayed verified";
  EXPECT_NE(find(**c, "site")->reason.find("removed or moved"), std::string::npos) << find(**c, "site")->reason;
  EXPECT_EQ((*c)->verified_path("site"), "");
  ASSERT_EQ(std::system(("rm -rf '" + dir + ".old'").c_str()), 0);

  const std::string gone = make_folder("removed");
  build(gone + "/site.vvp", 9);
  auto d = TerrainCatalogue::start(gone, 0);
  ASSERT_TRUE(d.ok());
  ASSERT_TRUE(wait_for(**d, "site", CatalogueState::verified));
  ASSERT_EQ(std::system(("rm -rf '" + gone + "'").c_str()), 0);
  ASSERT_TRUE(wait_for(**d, "site", std::nullopt));
}

// A verified pack whose file changes (rewritten in place, same name) is not
// switched to until verified again.
TEST(TerrainCatalogue, AVerifiedPackChangedSinceIsNotSwitchedTo) {
  const std::string dir = make_folder("changed");
  build(dir + "/site.vvp", 11);
  auto c = TerrainCatalogue::start(dir, 0);
  ASSERT_TRUE(c.ok());
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::verified));
  ASSERT_EQ((*c)->verified_path("site"), dir + "/site.vvp");
  damage_a_tile(dir + "/site.vvp");  // written in place: its status change time moves
  EXPECT_EQ((*c)->verified_path("site"), "") << "switched to before it was verified again";
  ASSERT_TRUE(wait_for(**c, "site", CatalogueState::refused));
}

// Stopped while it verifies: the destructor does not wait for the rest.
TEST(TerrainCatalogue, StopsWhileItVerifies) {
  const std::string dir = make_folder("stop");
  for (int k = 0; k < 6; ++k) build(dir + "/p" + std::to_string(k) + ".vvp", 10 + k);
  const auto t0 = std::chrono::steady_clock::now();
  {
    auto c = TerrainCatalogue::start(dir, 0);
    ASSERT_TRUE(c.ok());
    EXPECT_EQ((*c)->entries().size(), 6u) << "listed at start";
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
}

TEST(TerrainCatalogue, AFolderThatIsNotOneIsNamed) {
  auto missing = TerrainCatalogue::start("/nonexistent/visvol/terrains", 0);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("/nonexistent/visvol/terrains"), std::string::npos);
  const std::string file = ::testing::TempDir() + "/catalogue_file_" + std::to_string(getpid());
  std::ofstream(file) << "x";
  auto not_dir = TerrainCatalogue::start(file, 0);
  ASSERT_FALSE(not_dir.ok());
  EXPECT_NE(not_dir.status().message().find("not a folder"), std::string::npos);
  std::remove(file.c_str());
}

}  // namespace
}  // namespace visvol::app
