#include "rt/exec/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace visvol::rt {

namespace {

std::string errno_text(int e) { return std::string(std::strerror(e)); }

// Touches the stack below the caller so later calls never fault on it.
// noinline: the array must live in this frame, below the caller's.
__attribute__((noinline)) void prefault_stack(std::size_t bytes) {
  constexpr std::size_t kChunk = 16 * 1024;
  unsigned char buffer[kChunk];
  std::memset(buffer, 0, sizeof buffer);
  asm volatile("" : : "r"(buffer) : "memory");  // the writes must happen
  if (bytes > kChunk) prefault_stack(bytes - kChunk);
}

}  // namespace

void lock_process_memory(const RealtimeConfig& config, RealtimeReport& report) {
  if (!config.lock_memory) return;
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0) {
    report.memory_locked = true;
    return;
  }
  const int e = errno;
  report.warnings.push_back("memory not locked (mlockall: " + errno_text(e) +
                            "): pages may be swapped out and fault in the 1 kHz loop; run with "
                            "CAP_IPC_LOCK or a higher memlock limit (ulimit -l)");
}

void make_current_thread_realtime(const RealtimeConfig& config, RealtimeReport& report) {
  if (config.priority > 0) {
    sched_param sp{};
    sp.sched_priority = config.priority;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (rc == 0) {
      report.fifo = true;
    } else {
      report.warnings.push_back("SCHED_FIFO priority " + std::to_string(config.priority) + " refused (" +
                                errno_text(rc) +
                                "): the 1 kHz loop runs as an ordinary thread and other work can "
                                "delay it; run with CAP_SYS_NICE or an rtprio limit");
    }
  }
  if (config.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(config.cpu), &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (rc == 0) {
      report.pinned = true;
    } else {
      report.warnings.push_back("CPU " + std::to_string(config.cpu) + " affinity refused (" + errno_text(rc) +
                                "): the loop may migrate between CPUs");
    }
  }
  prefault_stack(config.stack_prefault_bytes);
}

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

ThreadFaults thread_faults() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return {u.ru_minflt, u.ru_majflt};
}

std::uint64_t resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long long size = 0, resident = 0;
  const int n = std::fscanf(f, "%llu %llu", &size, &resident);
  std::fclose(f);
  if (n != 2) return 0;
  return resident * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

}  // namespace visvol::rt
