// Shared pieces of the DDS tests: loopback participants in a namespace of
// this process, sample builders, waiting, and child processes.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/dds/participant.hpp"
#include "msg/samples.hpp"

extern char** environ;

namespace visvol::dds::test {

// "t<pid>": topics of this process only.
inline std::string process_namespace() { return "t" + std::to_string(::getpid()); }

inline ParticipantConfig loopback(std::uint32_t domain, const std::string& ns = process_namespace()) {
  ParticipantConfig c;
  c.domain_id = domain;
  c.cyclone_xml = std::string(loopback_config());
  c.topic_namespace = ns;
  return c;
}

// A participant or a failed test.
inline std::unique_ptr<Participant> make_participant(const ParticipantConfig& config) {
  Result<std::unique_ptr<Participant>> p = Participant::create(config);
  if (!p.ok()) {
    ADD_FAILURE() << p.status().message();
    return nullptr;
  }
  return std::move(*p);
}

// A straight path of `n` vertices along x with recognisable values.
inline void fill_path(msg::PathSample& s, std::uint64_t sequence, std::uint32_t n) {
  s.sequence = sequence;
  s.stamp_ns = 1700000000123456789LL + static_cast<std::int64_t>(sequence);
  msg::copy_text(s.pack_id, "sf_north");
  s.objective = msg::Objective::hide;
  s.converged = sequence % 2 == 0;
  s.f_c = 0.25 * static_cast<double>(sequence);
  s.length_m = 10.0 * n;
  s.min_clearance_m = 12.5;
  s.vertex_count = n;
  for (std::uint32_t i = 0; i < n; ++i) {
    s.vertices[i] =
        msg::PathVertex{{544000.0 + 10.0 * i, 4189000.0, 150.0 + static_cast<double>(sequence)}, 0.001 * i, 12.5 + i};
  }
}

inline std::unique_ptr<msg::PathSample> make_path(std::uint64_t sequence, std::uint32_t n) {
  auto s = std::make_unique<msg::PathSample>();
  *s = msg::PathSample{};
  fill_path(*s, sequence, n);
  return s;
}

// Polls `done` every millisecond until it holds or the timeout passes.
inline bool wait_until(const std::function<bool()>& done, double timeout_s) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::microseconds(static_cast<std::int64_t>(timeout_s * 1e6));
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return done();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// XCDR1 (plain CDR, as ROS 2 uses) little endian, built by the rules: a
// 4-byte encapsulation header {0x00, 0x01 (CDR_LE), 0x00, 0x00}, then each
// primitive aligned to its own size counted from the end of the header,
// strings as a uint32 length with the NUL, the bytes and the NUL, sequences as
// a uint32 count and the elements.
class Cdr {
 public:
  Cdr() : bytes_{0x00, 0x01, 0x00, 0x00} {}
  void u32(std::uint32_t v) { put(&v, 4); }
  void i32(std::int32_t v) { put(&v, 4); }
  void f64(double v) { put(&v, 8); }
  void str(const char* s) {
    const std::size_t n = std::strlen(s) + 1;
    u32(static_cast<std::uint32_t>(n));
    bytes_.insert(bytes_.end(), s, s + n);
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  void put(const void* v, std::size_t size) {
    while ((bytes_.size() - 4) % size != 0) bytes_.push_back(0);
    const auto* b = static_cast<const std::uint8_t*>(v);
    bytes_.insert(bytes_.end(), b, b + size);
  }
  std::vector<std::uint8_t> bytes_;
};

// The serialised nav_msgs/Path of a sample, by the rules above.
inline std::vector<std::uint8_t> path_cdr(const msg::PathSample& s, const char* frame_id) {
  Cdr cdr;
  const std::int64_t sec = s.stamp_ns / 1000000000;
  const std::uint32_t nsec = static_cast<std::uint32_t>(s.stamp_ns % 1000000000);
  cdr.i32(static_cast<std::int32_t>(sec));
  cdr.u32(nsec);
  cdr.str(frame_id);
  cdr.u32(s.vertex_count);
  for (std::uint32_t i = 0; i < s.vertex_count; ++i) {
    cdr.i32(static_cast<std::int32_t>(sec));
    cdr.u32(nsec);
    cdr.str(frame_id);
    cdr.f64(s.vertices[i].position.x_m);
    cdr.f64(s.vertices[i].position.y_m);
    cdr.f64(s.vertices[i].position.z_m);
    cdr.f64(0.0);  // orientation: identity
    cdr.f64(0.0);
    cdr.f64(0.0);
    cdr.f64(1.0);
  }
  return cdr.bytes();
}

inline std::string hex(const std::vector<std::uint8_t>& bytes) {
  static const char* kDigits = "0123456789abcdef";
  std::string out;
  for (const std::uint8_t b : bytes) {
    out += kDigits[b >> 4];
    out += kDigits[b & 15];
  }
  return out;
}

// A child process with its stdout and stderr captured.
class Child {
 public:
  explicit Child(const std::vector<std::string>& argv) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    out_fd_ = fds[0];
  }
  ~Child() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool started() const { return pid_ > 0; }

  // Waits for the exit, collecting output; kills the child after timeout_s.
  // Returns the exit status, or -1 when it had to be killed.
  int wait(double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<std::int64_t>(timeout_s * 1e3));
    while (!exited_) {
      drain(10);
      int status = 0;
      const pid_t r = ::waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        exited_ = true;
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
        exited_ = true;
        exit_code_ = -1;
        break;
      }
    }
    while (drain(0)) {
    }
    return exit_code_;
  }

  // Output so far (read while waiting).
  const std::string& output() const { return output_; }
  // Reads what is there within `ms` milliseconds; false at end of output.
  bool drain(int ms) {
    if (out_fd_ < 0) return false;
    pollfd p{out_fd_, POLLIN, 0};
    if (::poll(&p, 1, ms) <= 0) return false;
    char buf[4096];
    const ssize_t n = ::read(out_fd_, buf, sizeof buf);
    if (n <= 0) return false;
    output_.append(buf, static_cast<std::size_t>(n));
    return true;
  }
  // Waits (collecting output) until the output contains `text`.
  bool wait_for_output(const std::string& text, double timeout_s) {
    return wait_until(
        [&] {
          drain(1);
          return output_.find(text) != std::string::npos;
        },
        timeout_s);
  }

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
  std::string output_;
};

}  // namespace visvol::dds::test
