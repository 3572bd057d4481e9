// The console's terrain catalogue (--catalogue DIR): the packs in a folder
// (regular files named ID.vvp; names starting with a dot are a writer's
// temporary files and skipped), each opened and fully verified (every tile's
// checksum, the level the console runs on) on the catalogue's own thread,
// never the loop's. Packs added to the folder, replaced in it (written
// elsewhere and renamed over the old one, as `visvol build` does) or removed
// while the console runs are seen through inotify and verified again. A
// switch-terrain may name any verified entry; a refused one says why.
//
// Thread-safety: entries(), verified_path(), version() and wait_idle() from
// any thread but the real-time one (a mutex); start() and the destructor from
// one.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "base/status.hpp"
#include "fields/volume.hpp"

namespace visvol::app {

enum class CatalogueState { verifying, verified, refused };
const char* to_string(CatalogueState s);

struct CatalogueEntry {
  std::string id;  // the pack id: the file name less ".vvp"
  std::string path;
  CatalogueState state = CatalogueState::verifying;
  std::string reason;  // refused: what is wrong with it
  // Once the pack opened:
  std::string name;           // the DEM it was built from (file name)
  std::string crs;            // e.g. "EPSG:32610"
  std::string build_json;     // the build's parameters, as the pack records them
  fields::Bounds2D bounds;    // the finest level's posts, world metres
  fields::Bounds2D planning;  // where F_p counts every observer
  double post_spacing_m = 0;
  int levels = 0;
};

// Opens the pack at `path` and verifies it as the catalogue does: structure,
// every tile's checksum, `level` among its levels of detail; fills what it
// learned into `entry` (state verified, or refused with the reason).
void verify_catalogue_entry(const std::string& path, int level, CatalogueEntry& entry);

class TerrainCatalogue {
 public:
  // Watches `folder` and verifies what is in it. Errors: the folder cannot be
  // listed or watched (named).
  static Result<std::unique_ptr<TerrainCatalogue>> start(const std::string& folder, int level);
  ~TerrainCatalogue();
  TerrainCatalogue(const TerrainCatalogue&) = delete;
  TerrainCatalogue& operator=(const TerrainCatalogue&) = delete;

  const std::string& folder() const { return folder_; }
  // The entries by id.
  std::vector<CatalogueEntry> entries() const;
  // The path of the verified entry `id`; empty when there is none.
  std::string verified_path(const std::string& id) const;
  // Changes whenever an entry does (added, verified, refused, removed).
  std::uint64_t version() const { return version_.load(std::memory_order_acquire); }
  // Waits until nothing is left to verify, at most `timeout_s`; true if so.
  bool wait_idle(double timeout_s) const;

 private:
  TerrainCatalogue(std::string folder, int level, int inotify_fd, int wake_fd);
  void run();
  void scan();
  void handle_events();
  void enqueue(const std::string& file_name);
  void remove(const std::string& file_name);
  void verify_next();

  std::string folder_;
  int level_;
  int inotify_fd_ = -1, wake_fd_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> version_{0};
  mutable std::mutex mutex_;
  mutable std::condition_variable idle_;
  std::vector<CatalogueEntry> entries_;  // sorted by id
  std::deque<std::string> queue_;        // file names to verify
  std::thread thread_;
};

}  // namespace visvol::app
