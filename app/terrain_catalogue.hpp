// The console's terrain catalogue (--catalogue DIR): the packs in a folder
// (regular files named ID.vvp; names starting with a dot are a writer's
// temporary files and skipped), each opened and fully verified (every tile's
// checksum, read with pread so that a file changed meanwhile cannot fault
// the process; the level the console runs on) on the catalogue's own thread
// at idle CPU and I/O priority, never the loop's. Packs added to the folder,
// written in it, replaced (renamed over) or removed while the console runs
// are seen through inotify and verified again; a queue overflow lists the
// folder again. A switch-terrain may name any verified entry whose file is
// still the one verified (device, inode, size, status change time); a
// refused one says why.
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
#include "msg/samples.hpp"

namespace visvol::app {

using msg::CatalogueState;  // as the catalogue topic says it

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
  // The file that was verified.
  std::uint64_t device = 0, inode = 0, size_bytes = 0;
  std::int64_t changed_ns = 0;  // st_ctim: any write or rename sets it, nothing sets it back
};

// Opens the pack at `path` and verifies it as the catalogue does: structure,
// every tile's checksum, `level` among its levels of detail; fills what it
// learned into `entry` (state verified, or refused with the reason).
// `stop`, when set, ends a verification early (refused: "stopped"). A pack
// whose tables and heights exceed `max_pack_bytes` (0: no limit) is
// refused from its header and level table, before its tables are read.
void verify_catalogue_entry(const std::string& path, int level, CatalogueEntry& entry,
                            const std::atomic<bool>* stop = nullptr, std::uint64_t max_pack_bytes = 0);

class TerrainCatalogue {
 public:
  // Packs a catalogue keeps at most (the lowest ids of a folder listed;
  // then new ones as room is made); files beyond are left out and counted. A switch names at most 64, the published
  // catalogue lists 64: a folder of thousands of files would only cost the console's monitor time and locked memory.
  static constexpr std::size_t kMaxPacks = 256;

  // Watches `folder` and verifies what is in it. Errors: the folder cannot be
  // listed or watched (named).
  // `max_pack_bytes`: a pack whose tables and heights (Pack::footprint)
  // exceed it is refused before they are read (0: no limit).
  static Result<std::unique_ptr<TerrainCatalogue>> start(const std::string& folder, int level,
                                                         std::uint64_t max_pack_bytes = 0);
  ~TerrainCatalogue();
  TerrainCatalogue(const TerrainCatalogue&) = delete;
  TerrainCatalogue& operator=(const TerrainCatalogue&) = delete;

  const std::string& folder() const { return folder_; }
  // The entries by id.
  std::vector<CatalogueEntry> entries() const;
  // The path of the verified entry `id` while its file is the one verified;
  // empty otherwise.
  std::string verified_path(const std::string& id) const;
  // Changes whenever an entry does (added, verified, refused, removed).
  std::uint64_t version() const { return version_.load(std::memory_order_acquire); }
  // Whether `id` is an entry, in any state.
  bool has(const std::string& id) const;
  // Files left out because kMaxPacks were kept (counted each time one is seen).
  std::uint64_t left_out() const { return left_out_.load(std::memory_order_relaxed); }
  // Waits until nothing is left to verify, at most `timeout_s`; true if so.
  bool wait_idle(double timeout_s) const;

 private:
  TerrainCatalogue(std::string folder, int level, std::uint64_t max_pack_bytes, int inotify_fd, int wake_fd);
  void run();
  void scan(bool only_new = false);
  void rescan();
  void handle_events();
  void enqueue(const std::string& file_name);
  void being_written(const std::string& file_name);
  void remove(const std::string& file_name);
  void folder_gone();
  void verify_next();

  std::string folder_;
  int level_;
  std::uint64_t max_pack_bytes_;
  int inotify_fd_ = -1, wake_fd_ = -1;
  bool watching_ = true;  // false once the folder was removed or moved
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> version_{0};
  std::atomic<std::uint64_t> left_out_{0};
  mutable std::mutex mutex_;
  mutable std::condition_variable idle_;
  std::vector<CatalogueEntry> entries_;  // sorted by id
  std::deque<std::string> queue_;        // file names to verify
  bool busy_ = false;                    // one is being verified
  std::thread thread_;
};

}  // namespace visvol::app
