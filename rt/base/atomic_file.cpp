#include "rt/base/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace visvol {

namespace {

std::string directory_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

Status errno_status(const std::string& what, const std::string& path) {
  return io_error(path + ": " + what + ": " + std::strerror(errno));
}

Status fsync_path(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return errno_status("cannot open for fsync", path);
  const int rc = ::fsync(fd);
  const int saved = errno;
  ::close(fd);
  if (rc != 0) {
    errno = saved;
    return errno_status("fsync failed", path);
  }
  return Status::ok_status();
}

}  // namespace

std::string temp_path_for(const std::string& path) {
  return path + ".tmp." + std::to_string(::getpid());
}

Status commit_file(const std::string& temp_path, const std::string& path) {
  Status st = fsync_path(temp_path, O_RDONLY);
  if (!st.ok()) {
    discard_file(temp_path);
    return st;
  }
  if (std::rename(temp_path.c_str(), path.c_str()) != 0) {
    st = errno_status("cannot rename " + temp_path + " into place", path);
    discard_file(temp_path);
    return st;
  }
  // The rename is durable once the directory entry is.
  return fsync_path(directory_of(path), O_RDONLY | O_DIRECTORY);
}

void discard_file(const std::string& temp_path) { ::unlink(temp_path.c_str()); }

}  // namespace visvol

namespace visvol {

Status write_file_atomically(const std::string& path, const std::string& bytes) {
  const std::string temp = temp_path_for(path);
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (f == nullptr) return io_error(path + ": cannot write (" + std::strerror(errno) + ")");
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    discard_file(temp);
    return io_error(path + ": cannot write (" + std::strerror(errno) + ")");
  }
  return commit_file(temp, path);
}

}  // namespace visvol
