// A fixed histogram of durations for loop health: wake-up latency and compute
// time per tick. Bins are 1 us wide up to 1 ms, 10 us wide up to 10 ms and
// 100 us wide up to 100 ms; longer durations land in one overflow bin (their
// maximum is still exact). Percentiles are the upper edge of the bin that
// holds them, so they never understate.
//
// Ownership: a plain value (about 3.5 KiB). Thread-safety: one writer; copy
// it to hand it to another thread. Cost: add() is O(1), percentile() O(bins).
// add() and reset() are real-time safe.
#pragma once

#include <array>
#include <cstdint>

namespace visvol::rt {

class DurationHistogram {
 public:
  static constexpr int kFineBins = 1000;                                // 1 us each: [0, 1 ms)
  static constexpr int kMidBins = 900;                                  // 10 us each: [1 ms, 10 ms)
  static constexpr int kCoarseBins = 900;                               // 100 us each: [10 ms, 100 ms)
  static constexpr int kBins = kFineBins + kMidBins + kCoarseBins + 1;  // + overflow

  void add(std::int64_t duration_ns);
  void reset();

  std::uint64_t count() const { return count_; }
  double min_us() const { return count_ ? static_cast<double>(min_ns_) * 1e-3 : 0.0; }
  double max_us() const { return count_ ? static_cast<double>(max_ns_) * 1e-3 : 0.0; }
  double mean_us() const { return count_ ? static_cast<double>(sum_ns_) * 1e-3 / static_cast<double>(count_) : 0.0; }
  // The duration below which a fraction p (0..1) of the samples lie, us (the
  // upper edge of its bin, at most the maximum); 0 when empty.
  double percentile_us(double p) const;

  // Adds another histogram's samples (reports over several windows).
  void merge(const DurationHistogram& other);

 private:
  static int bin_of(std::int64_t ns);
  static double upper_edge_us(int bin);

  std::array<std::uint32_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  std::int64_t sum_ns_ = 0;
  std::int64_t min_ns_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace visvol::rt
