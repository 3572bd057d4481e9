#include "io/atomic_file.hpp"
#include "io/input_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>

namespace visvol {

namespace {

// --- names -------------------------------------------------------------------

std::string directory_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string base_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// This host's name as temporaries carry it: letters, digits and '-' kept,
// anything else (the dots of a domain) '_', at most 64 characters.
std::string host_label() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "unnamed";
  std::string out;
  for (const char* c = name; *c != '\0' && out.size() < 64; ++c) {
    const bool kept = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') || *c == '-';
    out += kept ? *c : '_';  // ASCII only, whatever the locale
  }
  return out;
}

const std::string& this_host() {
  static const std::string host = host_label();
  return host;
}

std::string temp_name_for(const std::string& path) { return temporary_prefix(path) + std::to_string(::getpid()); }

// Failures of the disk or the system, not of the path the user gave.
bool is_resource_errno(int e) {
  return e == ENOSPC || e == EDQUOT || e == EIO || e == EFBIG || e == ENOMEM || e == EMFILE || e == ENFILE;
}

Status errno_status(int e, const std::string& message) {
  const std::string text = message + ": " + std::strerror(e);
  return is_resource_errno(e) ? output_error(text) : invalid_argument(text);
}

// --- the live temporaries ------------------------------------------------------

// Every temporary this process has open, for the sweep (which must not remove
// one of its own that is still being written).
std::mutex g_live_mutex;
std::multiset<std::string> g_live;  // one entry per OutputFile, even of one name

// The same for the signal handler, which can neither lock nor allocate: fixed
// slots of paths, each guarded by a sequence number (odd while it changes) so
// the handler only acts on a path it read whole. A seqlock whose paths are
// atomics (a plain char array would be a data race when the signal lands on
// another thread than the writer's), written with release and read with
// acquire: a handler that reads a character written after the sequence went
// odd then sees the sequence odd or moved on, and its second read of the
// sequence cannot move before its reads of the path. No fences: GCC's
// ThreadSanitizer refuses them (and on x86 these are plain moves).
constexpr int kSlots = 16;
using PathChars = std::atomic<char>[PATH_MAX];
static_assert(std::atomic<char>::is_always_lock_free, "the signal handler reads paths without a lock");
struct Slot {
  std::atomic<bool> claimed{false};
  std::atomic<unsigned> sequence{0};
  PathChars file{};
  PathChars directory{};  // empty unless create_for_library
};
Slot g_slots[kSlots];

// `in` fits: the caller checked its size against PATH_MAX.
void store_path(PathChars& out, const std::string& in) {
  for (std::size_t i = 0; i <= in.size(); ++i) out[i].store(in.c_str()[i], std::memory_order_release);
}

// Async-signal-safe; the copy ends at the terminator (or PATH_MAX, terminated).
void load_path(const PathChars& in, char* out) {
  for (std::size_t i = 0; i < PATH_MAX; ++i) {
    out[i] = in[i].load(std::memory_order_acquire);
    if (out[i] == '\0') return;
  }
  out[PATH_MAX - 1] = '\0';
}

int register_live(const std::string& temp, const std::string& file, bool is_directory) {
  {
    std::lock_guard<std::mutex> lock(g_live_mutex);
    g_live.insert(temp);
  }
  if (file.size() >= PATH_MAX || temp.size() >= PATH_MAX) return -1;
  for (int n = 0; n < kSlots; ++n) {
    bool expected = false;
    if (!g_slots[n].claimed.compare_exchange_strong(expected, true)) continue;
    Slot& s = g_slots[n];
    s.sequence.fetch_add(1);  // odd: changing
    store_path(s.file, file);
    store_path(s.directory, is_directory ? temp : std::string());
    s.sequence.fetch_add(1);  // even: whole
    return n;
  }
  return -1;  // all slots busy: the sweep of a later run removes it
}

void unregister_live(const std::string& temp, int slot) {
  if (slot >= 0) {
    Slot& s = g_slots[slot];
    s.sequence.fetch_add(1);
    s.file[0].store('\0', std::memory_order_release);
    s.directory[0].store('\0', std::memory_order_release);
    s.sequence.fetch_add(1);
    s.claimed.store(false);
  }
  std::lock_guard<std::mutex> lock(g_live_mutex);
  const auto one = g_live.find(temp);  // this writer's entry, not another's of the same name
  if (one != g_live.end()) g_live.erase(one);
}

bool is_live(const std::string& temp) {
  std::lock_guard<std::mutex> lock(g_live_mutex);
  return g_live.count(temp) != 0;
}

// Unlinks every entry of the open directory `dir_fd`, never following one.
// Async-signal-safe (getdents64, unlinkat): the signal handler and the
// removals below share it.
void unlink_entries(int dir_fd) {
  alignas(dirent64) char entries[4096];
  ssize_t n = 0;
  while ((n = ::getdents64(dir_fd, entries, sizeof entries)) > 0) {
    for (ssize_t at = 0; at < n;) {
      const auto* e = reinterpret_cast<const dirent64*>(entries + at);
      at += e->d_reclen;
      const char* name = e->d_name;
      const bool dots = name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'));
      if (!dots) ::unlinkat(dir_fd, name, 0);
    }
  }
}

// The handler runs on names registered before they were created (so that no
// signal between the two leaves one behind): it removes only what this
// process could have made there, never through a link. All async-signal-safe
// (lstat, geteuid, unlink, open, fstat, getdents64, unlinkat, close, rmdir).

// A temporary file: a regular file of this user, else nothing.
void remove_file_in_handler(const char* file) {
  struct stat st {};
  if (::lstat(file, &st) == 0 && S_ISREG(st.st_mode) && st.st_uid == ::geteuid()) ::unlink(file);
}

// The private directory of create_for_library (this user's, closed to
// others), with what the library put in it (the file, GDAL's .aux.xml).
void remove_directory_in_handler(const char* directory) {
  const int fd = ::open(directory, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;  // absent, or a link planted at its name: left alone
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_uid != ::geteuid() || (st.st_mode & 077) != 0) {
    ::close(fd);
    return;
  }
  unlink_entries(fd);
  ::close(fd);
  ::rmdir(directory);
}

// Async-signal-safe: removes every temporary being written.
void remove_temporaries_in_handler() {
  for (Slot& s : g_slots) {
    if (!s.claimed.load()) continue;
    const unsigned before = s.sequence.load();
    if (before % 2 != 0) continue;
    char file[PATH_MAX];
    char directory[PATH_MAX];
    load_path(s.file, file);
    load_path(s.directory, directory);
    if (s.sequence.load(std::memory_order_relaxed) != before) continue;  // after the acquire reads above
    if (directory[0] != '\0') {
      remove_directory_in_handler(directory);  // the file is inside it
    } else if (file[0] != '\0') {
      remove_file_in_handler(file);
    }
  }
}

// While a set of files is renamed into place (write_files_atomically), a
// signal waits for the last rename (in whichever thread it arrives): kept
// here, raised again when the set is whole.
std::atomic<bool> g_renaming_set{false};
std::atomic<int> g_deferred_signal{0};

// Async-signal-safe: the removals above, signal and raise only.
extern "C" void remove_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  if (g_renaming_set.load()) {
    // kept first, then the flag read again: a set that ended meanwhile may
    // not have seen it, and this handler ends the process as below
    g_deferred_signal.store(sig);
    if (g_renaming_set.load()) {
      errno = saved_errno;
      return;
    }
  }
  remove_temporaries_in_handler();
  std::signal(sig, SIG_DFL);
  std::raise(sig);  // delivered with the default action once this returns
  errno = saved_errno;
}

// --- removal -------------------------------------------------------------------

// Empties and removes a private directory `name` in `parent_fd`; entries are
// unlinked, never followed.
void remove_private_directory(int parent_fd, const char* name) {
  const int fd = ::openat(parent_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd >= 0) {
    unlink_entries(fd);
    ::close(fd);
  }
  ::unlinkat(parent_fd, name, AT_REMOVEDIR);
}

void remove_temporary(const std::string& temp, bool is_directory) {
  if (!is_directory) {
    ::unlink(temp.c_str());
    return;
  }
  const int parent = ::open(directory_of(temp).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (parent < 0) return;
  remove_private_directory(parent, base_of(temp).c_str());
  ::close(parent);
}

bool process_runs(long pid) { return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM; }

// The pid of `name` when it is `prefix` followed by digits only, else -1.
long temporary_pid(const std::string& name, const std::string& prefix) {
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return -1;
  const std::string digits = name.substr(prefix.size());
  if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  const long pid = std::stol(digits);
  return pid > 0 ? pid : -1;
}

// A temporary of output `base` that a process of this host made, and its pid:
// `base.tmp.<this host>.<pid>`, or `base.tmp.<pid>` as versions before the host
// was in the name wrote them (`legacy`). Another host's (on a shared file
// system, whose pids mean nothing here) and any other name: -1.
long own_temporary_pid(const std::string& name, const std::string& base, bool& legacy) {
  const std::string prefix = base + ".tmp.";
  const long pid = temporary_pid(name, prefix + this_host() + ".");
  legacy = pid < 0;
  return legacy ? temporary_pid(name, prefix) : pid;
}

// --- checks ------------------------------------------------------------------

// The destination must be absent or a regular file; anything else is refused
// and left as it is.
Status check_destination(const std::string& path) {
  if (path.empty()) return invalid_argument("empty output file name");
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return Status::ok_status();
    return errno_status(errno, path + ": cannot be written");
  }
  if (!S_ISREG(st.st_mode)) {
    return invalid_argument(path + ": is " + file_kind(st.st_mode) +
                            ", not a regular file; refusing to replace it (left untouched)");
  }
  return Status::ok_status();
}

Status creation_error(int e, const std::string& path, const std::string& temp) {
  if (e == EEXIST) {
    struct stat st {};
    const bool seen = ::lstat(temp.c_str(), &st) == 0;
    return invalid_argument(path + ": the temporary " + temp + " already exists" +
                            (seen && !S_ISREG(st.st_mode) ? std::string(" (") + file_kind(st.st_mode) + ")" : "") +
                            "; not following or replacing it");
  }
  return errno_status(e, path + ": cannot create the temporary " + temp);
}

Status fsync_directory_of(const std::string& path) {
  const std::string dir = directory_of(path);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return output_error(dir + ": cannot open for fsync: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int e = errno;
  ::close(fd);
  // Some file systems cannot fsync a directory; the rename is done either way.
  if (rc != 0 && e != EINVAL && e != EROFS) {
    return output_error(dir + ": fsync failed: " + std::strerror(e));
  }
  return Status::ok_status();
}

}  // namespace

Status check_output_path(const std::string& path) {
  VISVOL_RETURN_IF_ERROR(check_destination(path));
  const std::string dir = directory_of(path);
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) return errno_status(errno, path + ": directory " + dir);
  if (!S_ISDIR(st.st_mode)) return invalid_argument(path + ": " + dir + " is not a directory");
  if (::access(dir.c_str(), W_OK) != 0) return errno_status(errno, path + ": directory " + dir);
  return Status::ok_status();
}

// --- OutputFile ------------------------------------------------------------------

Result<OutputFile> OutputFile::create(const std::string& path) {
  VISVOL_RETURN_IF_ERROR(check_destination(path));
  sweep_stale_temporaries(path);
  OutputFile f;
  f.path_ = path;
  f.temp_path_ = temp_name_for(path);
  f.write_path_ = f.temp_path_;
  // registered before it exists: a signal (to any thread) between the two
  // would otherwise leave it behind
  f.slot_ = register_live(f.temp_path_, f.write_path_, false);
  f.fd_ = ::open(f.temp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (f.fd_ < 0) {
    const int e = errno;
    unregister_live(f.temp_path_, f.slot_);
    f.slot_ = -1;
    return creation_error(e, path, f.temp_path_);
  }
  f.done_ = false;
  return f;
}

Result<OutputFile> OutputFile::create_for_library(const std::string& path) {
  VISVOL_RETURN_IF_ERROR(check_destination(path));
  sweep_stale_temporaries(path);
  OutputFile f;
  f.path_ = path;
  f.temp_path_ = temp_name_for(path);
  f.write_path_ = f.temp_path_ + "/" + base_of(path);
  f.is_directory_ = true;
  f.slot_ = register_live(f.temp_path_, f.write_path_, true);  // before it exists, as above
  if (::mkdir(f.temp_path_.c_str(), 0700) != 0) {
    const int e = errno;
    unregister_live(f.temp_path_, f.slot_);
    f.slot_ = -1;
    return creation_error(e, path, f.temp_path_);
  }
  f.done_ = false;
  return f;
}

Result<OutputFile> OutputFile::create_shared(const std::string& path) {
  Result<OutputFile> f = create_for_library(path);
  if (!f.ok()) return f;
  f->fd_ = ::open(f->write_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (f->fd_ < 0) {
    const int e = errno;
    f->discard();
    return creation_error(e, path, f->write_path_);
  }
  return f;
}

OutputFile::OutputFile(OutputFile&& other) noexcept { *this = std::move(other); }

OutputFile& OutputFile::operator=(OutputFile&& other) noexcept {
  if (this == &other) return *this;
  discard();
  path_ = std::move(other.path_);
  temp_path_ = std::move(other.temp_path_);
  write_path_ = std::move(other.write_path_);
  fd_ = other.fd_;
  slot_ = other.slot_;
  is_directory_ = other.is_directory_;
  done_ = other.done_;
  flushed_ = other.flushed_;
  renamed_ = other.renamed_;
  other.fd_ = -1;
  other.slot_ = -1;
  other.done_ = true;
  return *this;
}

OutputFile::~OutputFile() { discard(); }

Status OutputFile::fail(Status status) {
  discard();
  return status;
}

Status OutputFile::write(const void* data, std::size_t bytes) {
  flushed_ = false;
  if (done_ || fd_ < 0) return Status(Errc::state, path_ + ": output is closed");
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::write(fd_, p, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return fail(output_error(path_ + ": write failed: " + std::strerror(n < 0 ? errno : EIO)));
    p += n;
    bytes -= static_cast<std::size_t>(n);
  }
  return Status::ok_status();
}

Status OutputFile::write_at(const void* data, std::size_t bytes, std::uint64_t offset_bytes) {
  flushed_ = false;
  if (done_ || fd_ < 0) return Status(Errc::state, path_ + ": output is closed");
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::pwrite(fd_, p, bytes, static_cast<off_t>(offset_bytes));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return fail(output_error(path_ + ": write failed: " + std::strerror(n < 0 ? errno : EIO)));
    p += n;
    bytes -= static_cast<std::size_t>(n);
    offset_bytes += static_cast<std::uint64_t>(n);
  }
  return Status::ok_status();
}

Status OutputFile::commit() {
  if (done_) return Status(Errc::state, path_ + ": output is closed");
  // the data durable before the name points at it
  int fd = fd_;
  if (fd < 0) fd = ::open(write_path_.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return fail(errno_status(errno, path_ + ": the written file " + write_path_ + " is missing"));
  const bool synced = (flushed_ && fd == fd_) || ::fsync(fd) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd) == 0;
  const int close_errno = errno;
  fd_ = -1;
  if (!synced) return fail(output_error(path_ + ": fsync failed: " + std::strerror(sync_errno)));
  if (!closed) return fail(output_error(path_ + ": close failed: " + std::strerror(close_errno)));
  // something other than a regular file may have appeared there meanwhile
  if (Status st = check_destination(path_); !st.ok()) return fail(st);
  if (std::rename(write_path_.c_str(), path_.c_str()) != 0) {
    return fail(errno_status(errno, path_ + ": cannot rename " + write_path_ + " into place"));
  }
  renamed_ = true;
  if (is_directory_) remove_temporary(temp_path_, true);
  unregister_live(temp_path_, slot_);
  slot_ = -1;
  done_ = true;
  return fsync_directory_of(path_);
}

Status OutputFile::flush() {
  if (done_) return Status(Errc::state, path_ + ": output is closed");
  if (fd_ >= 0 && ::fsync(fd_) != 0) return fail(output_error(path_ + ": fsync failed: " + std::strerror(errno)));
  flushed_ = fd_ >= 0;
  return Status::ok_status();
}

void OutputFile::discard() {
  if (done_) return;
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  remove_temporary(temp_path_, is_directory_);
  unregister_live(temp_path_, slot_);
  slot_ = -1;
  done_ = true;
}

// --- the rest --------------------------------------------------------------------

Status write_file_atomically(const std::string& path, const std::string& bytes) {
  Result<OutputFile> f = OutputFile::create(path);
  if (!f.ok()) return f.status();
  VISVOL_RETURN_IF_ERROR(f->write(bytes.data(), bytes.size()));
  return f->commit();
}

void (*g_inside_rename_window_for_tests)() = nullptr;

Status write_files_atomically(const std::vector<std::pair<std::string, std::string>>& files,
                              const std::vector<std::string>& stale, std::vector<std::string>& written,
                              std::vector<std::string>& removed) {
  std::vector<OutputFile> ready;
  ready.reserve(files.size());
  for (const auto& [path, bytes] : files) {
    Result<OutputFile> f = OutputFile::create(path);
    if (!f.ok()) return f.status();  // the temporaries made so far go with `ready`
    VISVOL_RETURN_IF_ERROR(f->write(bytes.data(), bytes.size()));
    VISVOL_RETURN_IF_ERROR(f->flush());
    ready.push_back(std::move(*f));
  }
  // a signal between two renames would leave half of one set, half of another
  g_deferred_signal.store(0);
  g_renaming_set.store(true);
  // the stale files first: an interrupted set never keeps another's file
  // (an earlier flyable .plan beside a new path marked unmet)
  for (const std::string& file : stale) {
    struct stat st {};
    if (::lstat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || ::unlink(file.c_str()) != 0) continue;
    removed.push_back(file);
  }
  if (g_inside_rename_window_for_tests != nullptr) g_inside_rename_window_for_tests();
  Status status;
  for (OutputFile& f : ready) {
    status = f.commit();
    if (f.renamed()) written.push_back(f.path());  // in place, even where the folder's fsync failed after
    if (!status.ok()) break;
  }
  if (status.ok() && ready.empty() && !removed.empty()) status = fsync_directory_of(removed.front());
  g_renaming_set.store(false);
  if (const int sig = g_deferred_signal.exchange(0); sig != 0) {
    // an operator who pressed Ctrl-C to cancel must know the set was replaced
    std::fprintf(stderr, "interrupted (signal %d) as the outputs were renamed into place: %s:", sig,
                 status.ok() ? "written whole first" : "these were written before a failure");
    for (const std::string& f : written) std::fprintf(stderr, " %s", f.c_str());
    std::fprintf(stderr, "\n");
    std::fflush(stderr);  // (a stderr made fully buffered would lose it to the signal)
    std::raise(sig);
  }
  return status;
}

void install_output_cleanup_on_signals() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;  // nohup stays
    struct sigaction sa {};
    sa.sa_handler = remove_temporaries_and_reraise;
    sa.sa_flags = SA_RESTART;  // a signal deferred while a set is renamed returns: its system calls go on
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

namespace {
const char* g_fault_message = nullptr;

// Async-signal-safe: the removals, write and _exit only. A read past the
// end of a mapped file is BUS_ADRERR; any other SIGBUS (a memory error, a
// misaligned access) is not what the message says: the default action is
// restored and the fault repeats with it (a core where one is wanted).
extern "C" void remove_temporaries_and_exit(int sig, siginfo_t* info, void*) {
  if (info == nullptr || info->si_code != BUS_ADRERR) {
    std::signal(sig, SIG_DFL);
    return;
  }
  remove_temporaries_in_handler();
  if (g_fault_message != nullptr) {
    const ssize_t n = ::write(STDERR_FILENO, g_fault_message, std::strlen(g_fault_message));
    (void)n;
  }
  ::_exit(1);
}
}  // namespace

void install_mapped_read_fault_handler(const char* message) {
  g_fault_message = message;
  struct sigaction sa {};
  sa.sa_sigaction = remove_temporaries_and_exit;
  sa.sa_flags = SA_SIGINFO;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGBUS, &sa, nullptr);
}

std::string temporary_prefix(const std::string& path) { return path + ".tmp." + this_host() + "."; }

void sweep_stale_temporaries(const std::string& path) {
  const std::string base = base_of(path);
  DIR* d = ::opendir(directory_of(path).c_str());
  if (d == nullptr) return;
  const int dir_fd = ::dirfd(d);
  const long self = static_cast<long>(::getpid());
  while (const dirent* e = ::readdir(d)) {
    bool legacy = false;
    const long pid = own_temporary_pid(e->d_name, base, legacy);
    if (pid < 0) continue;
    // one of ours that is still being written, or one of another running process
    if (pid == self ? !legacy && is_live(temp_name_for(path)) : process_runs(pid)) continue;
    struct stat st {};
    if (::fstatat(dir_fd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;
    if (st.st_uid != ::geteuid()) continue;  // never another user's files
    if (S_ISREG(st.st_mode)) {
      ::unlinkat(dir_fd, e->d_name, 0);
    } else if (S_ISDIR(st.st_mode)) {
      remove_private_directory(dir_fd, e->d_name);
    }
  }
  ::closedir(d);
}

}  // namespace visvol
