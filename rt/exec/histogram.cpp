#include "rt/exec/histogram.hpp"

#include <algorithm>
#include <cmath>

namespace visvol::rt {

int DurationHistogram::bin_of(std::int64_t ns) {
  if (ns < 0) ns = 0;
  const std::int64_t us = ns / 1000;
  if (us < kFineBins) return static_cast<int>(us);
  if (us < 10'000) return kFineBins + static_cast<int>((us - 1000) / 10);
  if (us < 100'000) return kFineBins + kMidBins + static_cast<int>((us - 10'000) / 100);
  return kBins - 1;
}

double DurationHistogram::upper_edge_us(int bin) {
  if (bin < kFineBins) return bin + 1.0;
  if (bin < kFineBins + kMidBins) return 1000.0 + 10.0 * (bin - kFineBins + 1);
  if (bin < kBins - 1) return 10'000.0 + 100.0 * (bin - kFineBins - kMidBins + 1);
  return INFINITY;
}

void DurationHistogram::add(std::int64_t duration_ns) {
  if (duration_ns < 0) duration_ns = 0;
  std::uint32_t& b = bins_[static_cast<std::size_t>(bin_of(duration_ns))];
  if (b != UINT32_MAX) ++b;
  if (count_ == 0 || duration_ns < min_ns_) min_ns_ = duration_ns;
  if (count_ == 0 || duration_ns > max_ns_) max_ns_ = duration_ns;
  ++count_;
  sum_ns_ += duration_ns;
}

void DurationHistogram::reset() { *this = DurationHistogram(); }

double DurationHistogram::percentile_us(double p) const {
  if (count_ == 0) return 0.0;
  p = std::clamp(p, 0.0, 1.0);
  // the smallest bin whose cumulative count reaches ceil(p * count), at least 1
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(p * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[static_cast<std::size_t>(b)];
    if (seen >= rank) return std::min(upper_edge_us(b), max_us());
  }
  return max_us();
}

void DurationHistogram::merge(const DurationHistogram& other) {
  if (other.count_ == 0) return;
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    const std::uint64_t sum = std::uint64_t{bins_[b]} + other.bins_[b];
    bins_[b] = static_cast<std::uint32_t>(std::min<std::uint64_t>(sum, UINT32_MAX));
  }
  min_ns_ = count_ ? std::min(min_ns_, other.min_ns_) : other.min_ns_;
  max_ns_ = count_ ? std::max(max_ns_, other.max_ns_) : other.max_ns_;
  count_ += other.count_;
  sum_ns_ += other.sum_ns_;
}

}  // namespace visvol::rt
