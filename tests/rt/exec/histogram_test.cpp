#include "rt/exec/histogram.hpp"

#include <gtest/gtest.h>

#include <random>

namespace visvol::rt {
namespace {

TEST(DurationHistogram, EmptyReportsZeros) {
  DurationHistogram h;
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.percentile_us(0.99), 0.0);
  EXPECT_EQ(h.max_us(), 0.0);
}

TEST(DurationHistogram, PercentilesAreTheUpperEdgeOfTheirBin) {
  DurationHistogram h;
  for (int us = 1; us <= 100; ++us) h.add(us * 1000 + 300);  // 1.3 us .. 100.3 us
  EXPECT_EQ(h.count(), 100u);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.5), 51.0);  // the 50th sample is 50.3 us: bin [50, 51)
  EXPECT_DOUBLE_EQ(h.percentile_us(0.99), 100.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(1.0), 100.3);  // capped at the exact maximum
  EXPECT_DOUBLE_EQ(h.min_us(), 1.3);
  EXPECT_NEAR(h.mean_us(), 50.8, 1e-9);
}

TEST(DurationHistogram, NeverUnderstatesAPercentile) {
  std::mt19937 rng(3);
  std::lognormal_distribution<double> d(3.5, 1.2);  // tens of us with a long tail
  std::vector<std::int64_t> samples;
  DurationHistogram h;
  for (int i = 0; i < 20000; ++i) {
    const auto ns = static_cast<std::int64_t>(d(rng) * 1000.0);
    samples.push_back(ns);
    h.add(ns);
  }
  std::sort(samples.begin(), samples.end());
  for (double p : {0.5, 0.9, 0.99, 0.999}) {
    const double exact_us =
        static_cast<double>(samples[static_cast<std::size_t>(std::ceil(p * static_cast<double>(samples.size()))) - 1]) *
        1e-3;
    const double got = h.percentile_us(p);
    EXPECT_GE(got, exact_us) << p;
    // within one bin: 1 us below 1 ms, 10 us below 10 ms, 100 us below 100 ms
    const double bin = exact_us < 1000 ? 1.0 : exact_us < 10000 ? 10.0 : 100.0;
    EXPECT_LE(got, exact_us + bin + 1e-9) << p;
  }
}

TEST(DurationHistogram, LongAndNegativeDurations) {
  DurationHistogram h;
  h.add(-5);           // a clock step backwards counts as zero
  h.add(250'000'000);  // 250 ms: the overflow bin, exact maximum kept
  EXPECT_EQ(h.count(), 2u);
  EXPECT_DOUBLE_EQ(h.min_us(), 0.0);
  EXPECT_DOUBLE_EQ(h.max_us(), 250000.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(1.0), 250000.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.5), 1.0);
}

TEST(DurationHistogram, MergeEqualsAddingBoth) {
  DurationHistogram a, b, both;
  for (int i = 0; i < 500; ++i) {
    a.add(i * 1700);
    both.add(i * 1700);
    b.add(i * 23'000 + 5);
    both.add(i * 23'000 + 5);
  }
  a.merge(b);
  EXPECT_EQ(a.count(), both.count());
  EXPECT_DOUBLE_EQ(a.max_us(), both.max_us());
  EXPECT_DOUBLE_EQ(a.min_us(), both.min_us());
  for (double p : {0.1, 0.5, 0.9, 0.99}) EXPECT_DOUBLE_EQ(a.percentile_us(p), both.percentile_us(p));
}

}  // namespace
}  // namespace visvol::rt
