#include "io/input_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

namespace visvol {

const char* file_kind(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

Result<InputFile> InputFile::open(const std::string& path) {
  if (path.empty()) return invalid_argument("empty input file name");
  InputFile f;
  f.path_ = path;
  // O_NONBLOCK: a FIFO without a writer opens at once instead of waiting.
  f.fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (f.fd_ < 0) return io_error(path + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(f.fd_, &st) != 0) return io_error(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) {
    return invalid_argument(path + ": is " + file_kind(st.st_mode) + ", not a regular file");
  }
  // Reads of a regular file then behave as usual (and mmap does not care).
  const int flags = ::fcntl(f.fd_, F_GETFL);
  if (flags < 0 || ::fcntl(f.fd_, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    return io_error(path + ": " + std::strerror(errno));
  }
  f.size_bytes_ = static_cast<std::uint64_t>(st.st_size);
  return f;
}

InputFile::InputFile(InputFile&& other) noexcept { *this = std::move(other); }

InputFile& InputFile::operator=(InputFile&& other) noexcept {
  if (this == &other) return *this;
  if (fd_ >= 0) ::close(fd_);
  path_ = std::move(other.path_);
  fd_ = other.fd_;
  size_bytes_ = other.size_bytes_;
  other.fd_ = -1;
  return *this;
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

Result<std::string> InputFile::read_all(std::size_t max_bytes) {
  if (size_bytes_ > max_bytes) {
    return invalid_argument(path_ + ": " + std::to_string(size_bytes_) + " bytes, larger than the " +
                            std::to_string(max_bytes) + " allowed");
  }
  std::string text;
  text.reserve(static_cast<std::size_t>(size_bytes_));
  char buffer[64 * 1024];
  while (true) {
    const ssize_t n = ::read(fd_, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return io_error(path_ + ": read failed: " + std::strerror(errno));
    if (n == 0) break;
    // it may have grown since fstat
    if (text.size() + static_cast<std::size_t>(n) > max_bytes) {
      return invalid_argument(path_ + ": larger than the " + std::to_string(max_bytes) + " bytes allowed");
    }
    text.append(buffer, static_cast<std::size_t>(n));
  }
  return text;
}

Status InputFile::read_at(void* out, std::size_t bytes, std::uint64_t offset) const {
  auto* dst = static_cast<std::uint8_t*>(out);
  std::size_t got = 0;
  while (got < bytes) {
    const ssize_t n = ::pread(fd_, dst + got, bytes - got, static_cast<off_t>(offset + got));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return io_error(path_ + ": read failed: " + std::strerror(errno));
    if (n == 0) {
      return io_error(path_ + ": ended at byte " + std::to_string(offset + got) + ", " +
                      std::to_string(offset + bytes) + " expected (changed while read?)");
    }
    got += static_cast<std::size_t>(n);
  }
  return Status::ok_status();
}

Result<std::string> read_input_file(const std::string& path, std::size_t max_bytes) {
  Result<InputFile> f = InputFile::open(path);
  if (!f.ok()) return f.status();
  return f->read_all(max_bytes);
}

Status check_input_file(const std::string& path) {
  Result<InputFile> f = InputFile::open(path);
  return f.ok() ? Status::ok_status() : f.status();
}

Status check_side_files(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
  };
  const std::size_t dot = base.find_last_of('.');
  const std::string prefix = lower(dot == std::string::npos || dot == 0 ? base : base.substr(0, dot)) + ".";
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return Status::ok_status();  // the open of `path` names the problem
  Status status;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name == base || lower(name).rfind(prefix, 0) != 0) continue;
    const std::string side = dir + "/" + name;
    struct stat st {};
    if (::stat(side.c_str(), &st) != 0 || S_ISREG(st.st_mode) || S_ISDIR(st.st_mode)) continue;
    status = invalid_argument(side + ": is " + file_kind(st.st_mode) + ", not a regular file (a side file of " + path +
                              " that would be opened with it)");
    break;
  }
  ::closedir(d);
  return status;
}

}  // namespace visvol
