// Output files that appear whole or not at all, and never through a link.
//
// Every writer of visvol goes through OutputFile: it creates the temporary
// `PATH.tmp.<host>.<pid>` next to the destination with O_CREAT|O_EXCL|O_NOFOLLOW (so a
// link or file planted at that name is refused, never followed), refuses a
// destination that exists and is not a regular file (symlink, device, FIFO,
// directory: left untouched), and commit() fsyncs the data, renames it over the
// destination and fsyncs the directory. A crash or a kill before the rename
// leaves the old file (or none); the temporary is removed on every error, on
// SIGINT/SIGTERM where install_output_cleanup_on_signals() was called, and a
// later write to the same output sweeps those of dead processes of this host
// (the host's name in the temporary's: on a file system several hosts share,
// a pid that runs on another host means nothing here).
//
// Errors: Errc::invalid_argument when the path cannot be an output (not a
// regular file, no such directory, a planted temporary: bad input, exit 2);
// Errc::output when writing fails (disk full, I/O error: the operation failed,
// exit 1).
//
// Thread-safety: an OutputFile belongs to one thread; several may exist at once
// in different threads. Not real-time safe (blocking I/O, allocation).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "base/status.hpp"

namespace visvol {

class OutputFile {
 public:
  // A temporary open for writing (fd()) next to `path`.
  static Result<OutputFile> create(const std::string& path);

  // For a library that must create its file by path (GDAL): a private
  // directory `PATH.tmp.<host>.<pid>` (mode 0700, made with mkdir, which never follows
  // a link) and write_path() inside it, where nobody else can plant anything.
  // fd() is -1.
  static Result<OutputFile> create_for_library(const std::string& path);

  // For a file other processes of this user write too, opening it by name
  // (visvol-build-mpi's ranks): the file is made, open (fd()), at write_path()
  // inside such a private directory, where nobody else can put a link or
  // another file in its place.
  static Result<OutputFile> create_shared(const std::string& path);

  OutputFile(OutputFile&& other) noexcept;
  OutputFile& operator=(OutputFile&& other) noexcept;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();  // discards unless committed

  const std::string& path() const { return path_; }
  // Where the bytes go: the temporary file (or the file in the private directory).
  const std::string& write_path() const { return write_path_; }
  int fd() const { return fd_; }

  // Appends all `bytes` (retrying short writes and EINTR).
  Status write(const void* data, std::size_t bytes);
  // Writes all `bytes` at `offset_bytes`.
  Status write_at(const void* data, std::size_t bytes, std::uint64_t offset_bytes);

  // The bytes written so far made durable under the temporary (fsync): where
  // the disk is full, this fails before anything is renamed. On failure the
  // temporary is removed.
  Status flush();
  // fsync, rename over path(), fsync the directory. On failure the temporary is
  // removed and path() is untouched.
  Status commit();
  // Removes the temporary now (errors ignored); later calls do nothing.
  void discard();
  // commit() renamed it into place (true even where the folder's fsync failed after).
  bool renamed() const { return renamed_; }

 private:
  OutputFile() = default;
  Status fail(Status status);  // discards, then returns `status`

  std::string path_;
  std::string temp_path_;   // the name registered for cleanup: file or directory
  std::string write_path_;  // == temp_path_ for a file, inside it for a directory
  int fd_ = -1;
  int slot_ = -1;  // in the signal registry, or -1
  bool is_directory_ = false;
  bool done_ = true;      // committed or discarded
  bool flushed_ = false;  // flush() since the last write (write(), write_at()): commit need not fsync again
  bool renamed_ = false;  // commit() put it in place (its folder's fsync may still have failed)
};

// What OutputFile::create would refuse about `path` itself (an existing
// symlink, device, FIFO or directory; a directory that does not exist or
// cannot be written; an empty name),
// checked before long work so that a bad output name costs nothing. Creates
// nothing; the write itself checks again.
Status check_output_path(const std::string& path);

// Writes a whole file: `path` holds the old content or `bytes`, never part.
Status write_file_atomically(const std::string& path, const std::string& bytes);

// Writes a set of files (path, bytes) that belong together: each is written
// and made durable under its temporary first, and only when all are are the
// `stale` files of an earlier set removed (regular files only; `removed`
// lists them) and the new ones renamed into place, SIGINT, SIGTERM and SIGHUP
// (where install_output_cleanup_on_signals() was called, in any thread)
// waiting for the last rename. A full disk or a bad name leaves every
// destination as it was; `written` lists those renamed into place (a rename
// that fails after the stale files went leaves part of a set: rare, said).
Status write_files_atomically(const std::vector<std::pair<std::string, std::string>>& files,
                              const std::vector<std::string>& stale, std::vector<std::string>& written,
                              std::vector<std::string>& removed);

// For tests only (null otherwise): called by write_files_atomically inside
// the window where signals wait, after the stale files went and before the
// first rename, so a test can raise a signal exactly there.
extern void (*g_inside_rename_window_for_tests)();

// For offline tools: SIGINT and SIGTERM remove the temporaries being written,
// then end the process by the same signal. Call once at the start of main(),
// before any other handler is installed.
void install_output_cleanup_on_signals();

// For offline tools that read files through memory maps: a read of a mapped
// page that is no longer in the file (cut short or rewritten in place while
// read) faults with SIGBUS (BUS_ADRERR). Its handler removes the temporaries
// being written, prints `message` (a string that lives for the process) and
// exits 1: a line that says what happened, not a crash without a word. Any
// other SIGBUS takes the default action.
void install_mapped_read_fault_handler(const char* message);

// The name every temporary of `path` made on this host starts with, the pid
// following: `PATH.tmp.<host>.`, <host> this host's name with anything but
// letters, digits and '-' as '_' (at most 64 characters).
std::string temporary_prefix(const std::string& path);

// Removes `NAME.tmp.<host>.<pid>` temporaries next to `path` left by processes
// of this host that no longer run (regular files and the private directories
// of create_for_library, owned by this user), and the `NAME.tmp.<pid>` of
// earlier versions likewise; another host's are left. OutputFile::create
// calls it; public for tests.
void sweep_stale_temporaries(const std::string& path);

}  // namespace visvol
