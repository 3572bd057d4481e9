#include "app/terrain_catalogue.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <malloc.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/inotify.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>

#include "io/input_file.hpp"
#include "storage/pack_identity.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::app {
namespace {

constexpr const char* kPackSuffix = ".vvp";

// ID.vvp, not a dot file (a writer's temporary file, renamed when complete).
bool is_pack_name(const std::string& name) {
  const std::size_t n = std::strlen(kPackSuffix);
  return name.size() > n && name[0] != '.' && name.compare(name.size() - n, n, kPackSuffix) == 0;
}

std::string id_of(const std::string& file_name) {
  return file_name.substr(0, file_name.size() - std::strlen(kPackSuffix));
}

// What a pack id may be (the DDS commands' rule): 1..63 of [A-Za-z0-9._-].
bool valid_id(const std::string& id) { return !id.empty() && storage::pack_id_from_path(id + kPackSuffix) == id; }

std::string errno_text(const char* what, const std::string& path) {
  return std::string(what) + " " + path + ": " + std::strerror(errno);
}

void refuse(CatalogueEntry& e, const std::string& reason) {
  e.state = CatalogueState::refused;
  e.reason = reason;
}

// The pack's description: its source DEM, CRS, build parameters and extent.
void describe(const storage::Pack& pack, CatalogueEntry& e) {
  const storage::PackMetadata& m = pack.metadata();
  // kept as long as published at most (a pack's metadata may hold megabytes
  // there, and the catalogue's entries are locked memory, copied on each poll)
  auto at_most = [](const std::string& text, std::size_t capacity) {
    return text.size() < capacity ? text : text.substr(0, capacity - 1);
  };
  e.name = at_most(m.source_path.substr(m.source_path.find_last_of('/') + 1), msg::kCatalogueNameCapacity);
  e.crs = storage::epsg_from_wkt(m.crs_wkt);
  if (e.crs.empty()) e.crs = at_most(m.crs_name, msg::kCrsCapacity);
  const nlohmann::json meta = nlohmann::json::parse(m.json, nullptr, false);
  std::string build = meta.is_object() && meta.contains("build") ? meta["build"].dump() : "{}";
  // published whole or not at all: JSON cut short is no JSON
  e.build_json = build.size() < msg::kCatalogueBuildCapacity ? std::move(build) : std::string("{}");
  const fields::VolumeGeometry g = pack.geometry(0);
  e.bounds = {g.origin_x, g.origin_y - (g.ny - 1) * g.spacing_m, g.origin_x + (g.nx - 1) * g.spacing_m, g.origin_y};
  e.planning = m.planning.box;
  e.post_spacing_m = g.spacing_m;
  e.levels = pack.level_count();
}

// Every tile checked as read with pread into one buffer: through a mapping,
// a file truncated or rewritten meanwhile would raise SIGBUS, and every page
// read would count against the console's memory (locked, with mlockall's
// MCL_FUTURE). The page cache is told the file is read once.
Status verify_tiles_read(const storage::Pack& pack, const std::atomic<bool>* stop) {
  Result<InputFile> file = InputFile::open(pack.path());
  if (!file.ok()) return file.status();
  posix_fadvise(file->fd(), 0, 0, POSIX_FADV_SEQUENTIAL);
  std::vector<std::uint8_t> buf;
  Status result;
  for (std::uint64_t n = 0; n < pack.tile_count() && result.ok(); ++n) {
    if (stop != nullptr && stop->load(std::memory_order_relaxed)) {
      result = io_error("stopped");
      break;
    }
    const storage::TileEntry& t = pack.tile_entry(n);
    buf.resize(t.bytes);
    result = file->read_at(buf.data(), buf.size(), t.offset);
    if (!result.ok()) {
      result = io_error(storage::Pack::describe(t) + ": " + result.message());
    } else {
      result = pack.verify_tile_bytes(t, buf.data());
    }
  }
  posix_fadvise(file->fd(), 0, 0, POSIX_FADV_DONTNEED);
  return result;
}

// The verifier yields to everything else: the loop, the pager's reads (not
// SCHED_IDLE: the main thread takes its mutex, and would wait on a thread
// that a busy machine never runs).
void run_at_idle_priority() {
  sched_param none{};
  pthread_setschedparam(pthread_self(), SCHED_BATCH, &none);
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
  constexpr int kIoprioWhoProcess = 1, kIoprioClassIdle = 3, kIoprioClassShift = 13;
  syscall(SYS_ioprio_set, kIoprioWhoProcess, 0, kIoprioClassIdle << kIoprioClassShift);  // this thread
}

bool same_file(const CatalogueEntry& e, const struct stat& st) {
  return e.device == st.st_dev && e.inode == st.st_ino && e.size_bytes == static_cast<std::uint64_t>(st.st_size) &&
         e.changed_ns == static_cast<std::int64_t>(st.st_ctim.tv_sec) * 1'000'000'000 + st.st_ctim.tv_nsec;
}

}  // namespace

void verify_catalogue_entry(const std::string& path, int level, CatalogueEntry& e, const std::atomic<bool>* stop,
                            std::uint64_t max_pack_bytes) {
  e.path = path;
  e.state = CatalogueState::verifying;
  e.reason.clear();
  if (!valid_id(e.id)) {
    return refuse(e, "'" + e.id + "' is not a pack id (1..63 of A-Z a-z 0-9 . _ -): rename the file");
  }
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return refuse(e, errno_text("cannot read", path));
  if (!S_ISREG(st.st_mode)) return refuse(e, path + " is not a regular file");
  e.device = st.st_dev;
  e.inode = st.st_ino;
  e.size_bytes = static_cast<std::uint64_t>(st.st_size);
  e.changed_ns = static_cast<std::int64_t>(st.st_ctim.tv_sec) * 1'000'000'000 + st.st_ctim.tv_nsec;
  // A pack too large for the console's budget, from its header and level
  // table: its tables are held while it is verified (a 32768 x 32768 grid's
  // 214 MB tile table and 4 GiB of heights took a console over its budget).
  if (max_pack_bytes > 0) {
    Result<storage::PackFootprint> size = storage::Pack::footprint(path);
    if (!size.ok()) return refuse(e, size.status().message());
    const std::uint64_t held = size->table_bytes + size->height_bytes;
    if (held > max_pack_bytes) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "its tables and heights need %.0f MiB, over the console's %.0f MiB memory budget "
                    "(--budget-mib)",
                    static_cast<double>(held) / 1048576.0, static_cast<double>(max_pack_bytes) / 1048576.0);
      return refuse(e, text);
    }
  }
  // not mapped: the header, tables and height tiles read with pread
  Result<std::shared_ptr<const storage::Pack>> pack = storage::Pack::open(path, storage::PackAccess::inspect);
  if (!pack.ok()) return refuse(e, pack.status().message());
  describe(**pack, e);
  if (level >= (*pack)->level_count()) {
    return refuse(e, std::to_string((*pack)->level_count()) + " levels of detail: the console runs on level " +
                         std::to_string(level));
  }
  if (Status s = storage::check_planning_bounds(**pack); !s.ok()) return refuse(e, s.message());
  if (Status s = verify_tiles_read(**pack, stop); !s.ok()) return refuse(e, s.message());
  // changed while it was read: verified again when the change is seen
  if (stat(path.c_str(), &st) != 0 || !same_file(e, st)) return refuse(e, path + " changed while it was verified");
  e.state = CatalogueState::verified;
}

Result<std::unique_ptr<TerrainCatalogue>> TerrainCatalogue::start(const std::string& folder, int level,
                                                                  std::uint64_t max_pack_bytes) {
  struct stat st {};
  if (stat(folder.c_str(), &st) != 0) return invalid_argument("--catalogue " + errno_text("cannot read", folder));
  if (!S_ISDIR(st.st_mode)) return invalid_argument("--catalogue " + folder + ": not a folder");
  const int in = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (in < 0) return resource_error("--catalogue " + errno_text("cannot watch", folder));
  // written in place (closed), renamed in or out, deleted; the folder itself going
  const std::uint32_t mask =
      IN_MODIFY | IN_CLOSE_WRITE | IN_MOVED_TO | IN_MOVED_FROM | IN_DELETE | IN_DELETE_SELF | IN_MOVE_SELF | IN_ONLYDIR;
  if (inotify_add_watch(in, folder.c_str(), mask) < 0) {
    const std::string e = errno_text("cannot watch", folder);
    close(in);
    return invalid_argument("--catalogue " + e);
  }
  const int wake = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake < 0) {
    close(in);
    return resource_error("--catalogue: eventfd: " + std::string(std::strerror(errno)));
  }
  std::unique_ptr<TerrainCatalogue> c(new TerrainCatalogue(folder, level, max_pack_bytes, in, wake));
  c->scan();  // listed before start() returns: entries() shows every pack there (verifying)
  c->thread_ = std::thread([p = c.get()] { p->run(); });
  return c;
}

TerrainCatalogue::TerrainCatalogue(std::string folder, int level, std::uint64_t max_pack_bytes, int inotify_fd,
                                   int wake_fd)
    : folder_(std::move(folder)),
      level_(level),
      max_pack_bytes_(max_pack_bytes),
      inotify_fd_(inotify_fd),
      wake_fd_(wake_fd) {}

TerrainCatalogue::~TerrainCatalogue() {
  stop_.store(true);
  const std::uint64_t one = 1;
  if (write(wake_fd_, &one, sizeof one) < 0) {
    // the counter is full: the thread is awake already
  }
  if (thread_.joinable()) thread_.join();
  close(inotify_fd_);
  close(wake_fd_);
}

std::vector<CatalogueEntry> TerrainCatalogue::entries() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_;
}

std::string TerrainCatalogue::verified_path(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const CatalogueEntry& e : entries_) {
    struct stat st {};
    if (e.id == id && e.state == CatalogueState::verified && stat(e.path.c_str(), &st) == 0 && same_file(e, st)) {
      return e.path;
    }
  }
  return {};
}

bool TerrainCatalogue::has(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::any_of(entries_.begin(), entries_.end(), [&](const CatalogueEntry& e) { return e.id == id; });
}

bool TerrainCatalogue::wait_idle(double timeout_s) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return idle_.wait_for(lock, std::chrono::duration<double>(timeout_s), [this] { return queue_.empty() && !busy_; });
}

// After lost events: entries whose file is gone are removed, every file there
// is verified again.
void TerrainCatalogue::rescan() {
  std::vector<std::string> ids;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const CatalogueEntry& e : entries_) ids.push_back(e.id);
  }
  for (const std::string& id : ids) {
    struct stat st {};
    if (stat((folder_ + "/" + id + kPackSuffix).c_str(), &st) != 0) remove(id + kPackSuffix);
  }
  scan();
}

// Every pack file of the folder, in id order (the lowest ids are the ones
// kept when there are more than kMaxPacks); `only_new`: those not yet entries.
void TerrainCatalogue::scan(bool only_new) {
  DIR* d = opendir(folder_.c_str());
  if (d == nullptr) return;  // start() checked it; a folder gone since is seen by inotify
  std::vector<std::string> names;
  while (const dirent* de = readdir(d)) {
    const std::string name = de->d_name;
    if (is_pack_name(name) && !(only_new && has(id_of(name)))) names.push_back(name);
  }
  closedir(d);
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) { return id_of(a) < id_of(b); });
  for (const std::string& name : names) enqueue(name);
}

void TerrainCatalogue::enqueue(const std::string& file_name) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string id = id_of(file_name);
  auto it = std::lower_bound(entries_.begin(), entries_.end(), id,
                             [](const CatalogueEntry& e, const std::string& key) { return e.id < key; });
  if (it == entries_.end() || it->id != id) {
    if (entries_.size() >= kMaxPacks) {
      left_out_.fetch_add(1, std::memory_order_relaxed);
      version_.fetch_add(1, std::memory_order_acq_rel);
      return;
    }
    it = entries_.insert(it, CatalogueEntry{});
  }
  *it = CatalogueEntry{};
  it->id = id;
  it->path = folder_ + "/" + file_name;
  if (std::find(queue_.begin(), queue_.end(), file_name) == queue_.end()) queue_.push_back(file_name);
  version_.fetch_add(1, std::memory_order_acq_rel);
}

// Written to (not yet closed): not to be switched to until verified again.
void TerrainCatalogue::being_written(const std::string& file_name) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string id = id_of(file_name);
  for (CatalogueEntry& e : entries_) {
    if (e.id == id && e.state != CatalogueState::verifying) {
      e.state = CatalogueState::verifying;
      e.reason.clear();
      version_.fetch_add(1, std::memory_order_acq_rel);
    }
  }
}

// The folder itself was removed or moved: its packs are no longer there to
// switch to (the watch ends with it).
void TerrainCatalogue::folder_gone() {
  std::lock_guard<std::mutex> lock(mutex_);
  watching_ = false;
  queue_.clear();
  for (CatalogueEntry& e : entries_) refuse(e, folder_ + " was removed or moved");
  version_.fetch_add(1, std::memory_order_acq_rel);
  idle_.notify_all();
}

void TerrainCatalogue::remove(const std::string& file_name) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string id = id_of(file_name);
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(), [&](const CatalogueEntry& e) { return e.id == id; }),
                 entries_.end());
  queue_.erase(std::remove(queue_.begin(), queue_.end(), file_name), queue_.end());
  version_.fetch_add(1, std::memory_order_acq_rel);
  idle_.notify_all();
}

void TerrainCatalogue::verify_next() {
  std::string file_name;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.empty()) return;
    file_name = queue_.front();
    queue_.pop_front();
    busy_ = true;
  }
  CatalogueEntry e;
  e.id = id_of(file_name);
  // an exception on this thread would end the console: a pack whose sizes
  // ask for more memory than there is is refused like any other bad pack
  try {
    verify_catalogue_entry(folder_ + "/" + file_name, level_, e, &stop_, max_pack_bytes_);
  } catch (const std::exception& ex) {
    refuse(e, folder_ + "/" + file_name + ": cannot be verified: " + ex.what());
  }
  // The pack's tables were heap memory, locked like all of it (mlockall's
  // MCL_FUTURE): handed back to the system rather than kept by this thread's
  // arena.
  malloc_trim(0);
  std::lock_guard<std::mutex> lock(mutex_);
  busy_ = false;
  // (removed meanwhile: no entry takes it; changed since: verified_path()
  // compares the file's identity, and the change's event verifies it again)
  for (CatalogueEntry& old : entries_) {
    if (old.id == e.id && watching_) old = std::move(e);
  }
  version_.fetch_add(1, std::memory_order_acq_rel);
  idle_.notify_all();
}

void TerrainCatalogue::handle_events() {
  alignas(inotify_event) char buf[16 * (sizeof(inotify_event) + 256)];
  for (;;) {
    const ssize_t n = read(inotify_fd_, buf, sizeof buf);
    if (n <= 0) return;  // EAGAIN: all read
    for (const char* p = buf; p < buf + n;) {
      inotify_event ev{};
      std::memcpy(&ev, p, sizeof ev);
      const std::string name = ev.len > 0 ? std::string(p + sizeof ev) : std::string();
      p += sizeof ev + ev.len;
      if (ev.mask & IN_Q_OVERFLOW) {
        rescan();  // events were lost: the folder as it is now
        continue;
      }
      if (ev.mask & (IN_DELETE_SELF | IN_MOVE_SELF | IN_IGNORED)) {
        folder_gone();
        return;
      }
      if (!is_pack_name(name)) continue;
      if (ev.mask & IN_MODIFY) being_written(name);
      if (ev.mask & (IN_CLOSE_WRITE | IN_MOVED_TO)) enqueue(name);
      if (ev.mask & (IN_MOVED_FROM | IN_DELETE)) {
        remove(name);
        // room for one left out: the folder's first new id in order takes it
        if (left_out_.load(std::memory_order_relaxed) > 0) scan(true);
      }
    }
  }
}

void TerrainCatalogue::run() {
  run_at_idle_priority();
  while (!stop_.load()) {
    bool pending = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pending = !queue_.empty();
    }
    pollfd fds[2] = {{wake_fd_, POLLIN, 0}, {inotify_fd_, POLLIN, 0}};
    // events first (a file replaced again need not be verified twice), then
    // one verification; the folder gone, the stop alone is waited for
    if (poll(fds, watching_ ? 2 : 1, pending ? 0 : -1) < 0 && errno != EINTR) return;
    if (stop_.load()) return;
    if (watching_ && (fds[1].revents & POLLIN)) handle_events();
    verify_next();
  }
}

}  // namespace visvol::app
