// What makes a thread real-time on Linux, each step taken when permitted and
// reported when not: SCHED_FIFO at a priority, CPU affinity, memory locked
// (mlockall), a prefaulted stack. Without the privilege (no CAP_SYS_NICE,
// CAP_IPC_LOCK or rtprio limit) the console still runs, with a warning that
// says what is missing and what it costs.
//
// Thread-safety: lock_process_memory() once from main before threads start;
// make_current_thread_realtime() on the thread concerned. monotonic_ns() and
// thread_faults() are real-time safe (vDSO and one non-blocking system call).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace visvol::rt {

struct RealtimeConfig {
  int priority = 80;                              // SCHED_FIFO priority 1..99; 0 keeps SCHED_OTHER
  int cpu = -1;                                   // pin to this CPU; -1 leaves the affinity alone
  bool lock_memory = true;                        // mlockall: no page of the process is paged out
  std::size_t stack_prefault_bytes = 256 * 1024;  // touched once so the stack never faults
};

struct RealtimeReport {
  bool memory_locked = false;
  bool fifo = false;
  bool pinned = false;
  std::vector<std::string> warnings;  // one line each: what failed, why, what it costs
};

// mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT): pages are locked as they
// are first touched, so a large read-only mapping (a field pack) is not
// pulled in whole; the tile pager locks what the real-time thread reads.
void lock_process_memory(const RealtimeConfig& config, RealtimeReport& report);

// SCHED_FIFO, affinity and the stack prefault for the calling thread.
void make_current_thread_realtime(const RealtimeConfig& config, RealtimeReport& report);

// CLOCK_MONOTONIC in nanoseconds.
std::int64_t monotonic_ns();

// Page faults of the calling thread so far (getrusage(RUSAGE_THREAD)).
struct ThreadFaults {
  std::int64_t minor = 0;
  std::int64_t major = 0;
};
ThreadFaults thread_faults();

// Resident set size of the process, bytes (/proc/self/statm). Not real-time
// safe (file I/O).
std::uint64_t resident_bytes();

}  // namespace visvol::rt
