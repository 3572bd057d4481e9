// Input files opened without ever blocking on something that is not a file.
//
// open() of a FIFO for reading waits for a writer, for ever; of a device, it
// may do anything. Every input of visvol is opened here: O_RDONLY|O_NONBLOCK,
// fstat, refused unless a regular file ("x: is a FIFO, not a regular file"),
// then O_NONBLOCK cleared. A symbolic link to a regular file is accepted.
//
// Errors: Errc::io when the file cannot be opened (the OS's reason, naming the
// path); Errc::invalid_argument when it is not a regular file or too large.
//
// Thread-safety: an InputFile belongs to one thread. Not real-time safe.
#pragma once

#include <sys/types.h>
#include <cstddef>
#include <cstdint>

#include <string>

#include "base/status.hpp"

namespace visvol {

class InputFile {
 public:
  static Result<InputFile> open(const std::string& path);

  InputFile(InputFile&& other) noexcept;
  InputFile& operator=(InputFile&& other) noexcept;
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  int fd() const { return fd_; }
  std::uint64_t size_bytes() const { return size_bytes_; }
  const std::string& path() const { return path_; }

  // The whole file; Errc::invalid_argument naming the limit when it is larger
  // than `max_bytes`.
  Result<std::string> read_all(std::size_t max_bytes);
  // Exactly `bytes` at `offset` (pread: the file position is left alone), or
  // Errc::io naming the path: a read error, or the file ending first (changed
  // since it was opened).
  Status read_at(void* out, std::size_t bytes, std::uint64_t offset) const;

 private:
  InputFile() = default;
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_bytes_ = 0;
};

// The whole of the regular file `path`, at most `max_bytes`.
Result<std::string> read_input_file(const std::string& path, std::size_t max_bytes);

// For a library that opens by path itself (GDAL, CLI11's config reader): the
// same check, opening and closing the file, before handing the path over.
Status check_input_file(const std::string& path);

// Libraries also open side files by name next to `path` (GDAL: DEM.prj,
// DEM.hdr, DEM.tif.aux.xml, DEM.tfw...): any entry of the same stem (the name
// up to its last '.', case ignored) that is a FIFO, device or socket is refused
// naming it, since opening it would block or worse.
Status check_side_files(const std::string& path);

// What a file that is not a regular one is, for messages: "a symbolic link",
// "a directory", "a FIFO", "a character device", "a block device", "a socket"
// (inputs and outputs alike).
const char* file_kind(mode_t mode);

}  // namespace visvol
