// Counts heap allocations made through operator new, to prove that real-time
// code does not allocate. Linking the library `visvol_alloc_counter` replaces
// the global operator new/delete of that binary (tests and benchmarks only;
// never linked into the console).
#pragma once

#include <cstdint>

namespace visvol::testing {

// Allocations since the program started (all threads).
std::uint64_t allocation_count();
// Allocations made by the calling thread since it started.
std::uint64_t thread_allocation_count();

}  // namespace visvol::testing
