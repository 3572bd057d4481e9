#include "base/handoff.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace visvol {
namespace {

struct Sample {
  std::uint64_t seq;
  std::uint64_t check;  // seq * 3 + 1: a torn copy would break it
  double payload[30];
};

TEST(LatestValue, NothingUntilPublished) {
  LatestValue<Sample> lv;
  EXPECT_EQ(lv.take(), nullptr);
  lv.write(Sample{7, 22, {}});
  const Sample* s = lv.take();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->seq, 7u);
  EXPECT_EQ(lv.take(), nullptr);  // nothing new since
}

TEST(LatestValue, NewestWins) {
  LatestValue<Sample> lv;
  for (std::uint64_t n = 1; n <= 5; ++n) lv.write(Sample{n, n * 3 + 1, {}});
  const Sample* s = lv.take();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->seq, 5u);
}

TEST(LatestValue, ConcurrentReaderSeesWholeIncreasingValues) {
  LatestValue<Sample> lv;
  constexpr std::uint64_t kCount = 200000;
  std::thread producer([&] {
    for (std::uint64_t n = 1; n <= kCount; ++n) {
      Sample& s = lv.back();
      s.seq = n;
      for (double& p : s.payload) p = static_cast<double>(n);
      s.check = n * 3 + 1;
      lv.publish();
    }
  });
  std::uint64_t last = 0, seen = 0;
  while (last < kCount) {
    if (const Sample* s = lv.take()) {
      ASSERT_EQ(s->check, s->seq * 3 + 1);
      ASSERT_EQ(s->payload[29], static_cast<double>(s->seq));
      ASSERT_GT(s->seq, last);
      last = s->seq;
      ++seen;
    }
  }
  producer.join();
  EXPECT_GT(seen, 0u);
}

TEST(SpscQueue, FifoAndFullDrops) {
  SpscQueue<int, 4> q;
  for (int n = 0; n < 4; ++n) EXPECT_TRUE(q.try_push(n));
  EXPECT_FALSE(q.try_push(99));  // full: dropped, nothing overwritten
  int v = -1;
  for (int n = 0; n < 4; ++n) {
    ASSERT_TRUE(q.try_pop(v));
    EXPECT_EQ(v, n);
  }
  EXPECT_FALSE(q.try_pop(v));
}

TEST(SpscQueue, ConcurrentTransferKeepsOrderAndCountsDrops) {
  SpscQueue<std::uint64_t, 64> q;
  constexpr std::uint64_t kCount = 300000;
  std::atomic<std::uint64_t> dropped{0};
  std::thread producer([&] {
    for (std::uint64_t n = 0; n < kCount; ++n) {
      if (!q.try_push(n)) dropped.fetch_add(1, std::memory_order_relaxed);
    }
  });
  std::uint64_t received = 0, last = 0;
  bool first = true;
  auto drain = [&] {
    std::uint64_t v;
    while (q.try_pop(v)) {
      if (!first) {
        ASSERT_GT(v, last);
      }
      first = false;
      last = v;
      ++received;
    }
  };
  while (received + dropped < kCount) {
    drain();
    if (::testing::Test::HasFatalFailure()) break;
  }
  producer.join();
  drain();
  EXPECT_EQ(received + dropped, kCount);
}

}  // namespace
}  // namespace visvol
