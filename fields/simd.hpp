// What the field's vector kernels share (the hull kernel and the terrain
// force field's column search): GCC vector types of W lanes, a forced-inline
// attribute, and the pick of a kernel's build for the CPU it runs on.
#pragma once

#include <cstdint>

namespace visvol::fields::simd {

// W lanes of floats and doubles, and the integers of their widths (a
// comparison's result).
template <int W>
struct Lanes {
  typedef float F __attribute__((vector_size(W * sizeof(float))));
  typedef std::int32_t I __attribute__((vector_size(W * sizeof(std::int32_t))));
  typedef double D __attribute__((vector_size(W * sizeof(double))));
  typedef std::int64_t M __attribute__((vector_size(W * sizeof(std::int64_t))));
};

// Kernel helpers take vectors by reference and are always inlined: a vector
// wider than the baseline's registers must not cross a function boundary by
// value (that changes the ABI; clang refuses it, GCC warns).
#define VISVOL_SIMD_INLINE inline __attribute__((always_inline))
#define VISVOL_SIMD_INLINE_LAMBDA __attribute__((always_inline))

// A vector from or to memory aligned only as its elements are, in one
// instruction. Not memcpy: GCC 12 copies a 32-byte memcpy in 16-byte halves
// through the stack for a v3 (AVX2) target, and the whole-vector load that
// follows stalls on the two half stores (store forwarding): the AVX2 hull
// kernel spent a third of its time there on a Zen 3 host.
template <class V, class T>
VISVOL_SIMD_INLINE void load_unaligned(V& v, const T* p) {
  typedef V Unaligned __attribute__((aligned(alignof(T)), may_alias));
  v = *reinterpret_cast<const Unaligned*>(p);
}
template <class V, class T>
VISVOL_SIMD_INLINE void store_unaligned(T* p, const V& v) {
  typedef V Unaligned __attribute__((aligned(alignof(T)), may_alias));
  *reinterpret_cast<Unaligned*>(p) = v;
}

// GCC on x86-64 builds a kernel for each of x86-64 levels v4 (AVX-512) and
// v3 (AVX2) beside the baseline; other compilers and CPUs have the baseline.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define VISVOL_SIMD_DISPATCH 1

// The build of a kernel for this CPU: v4, else v3, else the baseline.
template <class Fn>
Fn pick_for_cpu(Fn v4, Fn v3, Fn baseline) {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return v4;
  if (__builtin_cpu_supports("x86-64-v3")) return v3;
  return baseline;
}
#endif

}  // namespace visvol::fields::simd
