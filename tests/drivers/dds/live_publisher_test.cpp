// The publisher thread with real Cyclone participants (domain 213, loopback).
#include <sys/resource.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "drivers/dds/live_publisher.hpp"
#include "drivers/dds/topics.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::fill_path;
using test::loopback;
using test::make_participant;
using test::make_path;
using test::wait_until;
constexpr std::uint32_t kDomain = test::kDomainLivePublisher;

// Takes every PathUpdate waiting (after waiting up to timeout_s for one).
std::vector<msg::PathSample> take_updates(const Reader& reader, double timeout_s) {
  std::vector<msg::PathSample> got;
  const Result<bool> ready = reader.wait(timeout_s);
  if (!ready.ok() || !*ready) return got;
  Result<int> n = reader.take<visvol_msgs_msg_dds__PathUpdate_>(
      [&](const visvol_msgs_msg_dds__PathUpdate_& msg, const dds_sample_info_t&) {
        auto s = std::make_unique<msg::PathSample>();
        EXPECT_TRUE(decode_path_update(msg, *s).ok());
        got.push_back(*s);
      });
  EXPECT_TRUE(n.ok());
  return got;
}

// Live publisher -----------------------------------------------------------------

long voluntary_switches() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u.ru_nvcsw;
}

// The producer side must never wait for DDS: 100000 hand-offs while the
// publisher thread converts and writes, with and without a subscriber, and
// not one voluntary context switch (a lock, a futex or a sleep would make one).
void expect_producer_never_waits(LivePublisher& pub) {
  const std::uint64_t before = pub.stats().paths;
  const long switches = voluntary_switches();
  for (std::uint64_t seq = 1; seq <= 100000; ++seq) {
    msg::PathSample& s = pub.path().back();
    fill_path(s, seq, 64);
    pub.path().publish();
    msg::HealthSample& h = pub.health().back();
    h.sequence = seq;
    pub.health().publish();
  }
  const long waited = voluntary_switches() - switches;
  // ThreadSanitizer's runtime takes locks of its own on every synchronising
  // access: a switch there is not the producer's.
#ifndef VISVOL_SANITIZED_THREAD
  EXPECT_EQ(waited, 0) << "the producer blocked " << waited << " times";
#else
  (void)waited;
#endif
  // ... while the publisher did publish meanwhile or right after
  EXPECT_TRUE(wait_until([&] { return pub.stats().paths > before; }, 5.0));
}

TEST(LivePublisher, ProducerNeverWaitsWithNobodySubscribed) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  PublisherConfig config;
  config.path_hz = 1000.0;  // publish as much as possible meanwhile
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, config);
  ASSERT_TRUE(pub.ok()) << pub.status().message();
  EXPECT_EQ((*pub)->path_subscribers(), 0u);
  expect_producer_never_waits(**pub);
  EXPECT_EQ((*pub)->stats().errors, 0u) << (*pub)->stats().last_error;
}

TEST(LivePublisher, ProducerNeverWaitsWithASubscriberThatNeverReads) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> idle = Reader::create(*p, Topic::path_update);
  ASSERT_TRUE(idle.ok());
  PublisherConfig config;
  config.path_hz = 1000.0;
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, config);
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE(idle->wait_for_writers(1, 5.0).ok());
  expect_producer_never_waits(**pub);
}

TEST(LivePublisher, PathRateIsAtMostTheConfiguredRate) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  QosPtr qos = reader_qos(Topic::path_update);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);  // count every one
  Result<Reader> reader = Reader::create(*p, Topic::path_update, qos.get());
  ASSERT_TRUE(reader.ok());
  PublisherConfig config;
  config.path_hz = 20.0;
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, config);
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE(reader->wait_for_writers(1, 5.0).ok());

  // a 1 kHz producer for 1 s
  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t seq = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(1)) {
    fill_path((*pub)->path().back(), ++seq, 16);
    (*pub)->path().publish();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE((*pub)->stop().ok());

  std::vector<std::uint64_t> sequences;
  wait_until(
      [&] {
        (void)reader->take<visvol_msgs_msg_dds__PathUpdate_>(
            [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
              sequences.push_back(m.sequence_number);
            });
        return !sequences.empty() && sequences.back() == seq;
      },
      5.0);
  // at most one per 50 ms, plus the last pass on stop
  EXPECT_LE(sequences.size(), static_cast<std::size_t>(elapsed_s * 20.0) + 2);
  EXPECT_GE(sequences.size(), 5u);
  ASSERT_FALSE(sequences.empty());
  EXPECT_EQ(sequences.back(), seq);  // the newest is never lost
  for (std::size_t i = 1; i < sequences.size(); ++i) EXPECT_GT(sequences[i], sequences[i - 1]);
}

// A publisher with the given path_refresh_wait_s and a keep-all reader of
// its path updates: the sequence numbers seen, in order.
struct PathWatch {
  std::unique_ptr<Participant> participant;
  std::unique_ptr<Reader> reader;
  std::unique_ptr<LivePublisher> pub;
  std::vector<std::uint64_t> seen;

  void start(double refresh_wait_s) {
    participant = make_participant(loopback(kDomain));
    ASSERT_NE(participant, nullptr);
    QosPtr qos = reader_qos(Topic::path_update);
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
    Result<Reader> r = Reader::create(*participant, Topic::path_update, qos.get());
    ASSERT_TRUE(r.ok());
    reader = std::make_unique<Reader>(std::move(*r));
    PublisherConfig config;
    config.path_refresh_wait_s = refresh_wait_s;
    Result<std::unique_ptr<LivePublisher>> p = LivePublisher::start(*participant, config);
    ASSERT_TRUE(p.ok());
    pub = std::move(*p);
    ASSERT_TRUE(reader->wait_for_writers(1, 5.0).ok());
  }
  void collect() {
    (void)reader->take<visvol_msgs_msg_dds__PathUpdate_>(
        [&](const visvol_msgs_msg_dds__PathUpdate_& m, const dds_sample_info_t&) {
          seen.push_back(m.sequence_number);
        });
  }
};

TEST(LivePublisher, StalePathWaitsBrieflyForANewerOne) {
  PathWatch w;
  ASSERT_NO_FATAL_FAILURE(w.start(0.1));
  std::unique_ptr<LivePublisher>* pub = &w.pub;
  std::vector<std::uint64_t>& seen = w.seen;
  const auto collect = [&] { w.collect(); };

  // a path stamped 10 ms before its hand-off is kept back ...
  msg::PathSample& stale = (*pub)->path().back();
  fill_path(stale, 1, 4);
  stale.stamp_ns = msg::now_stamp_ns() - 10000000;
  (*pub)->path().publish();
  ASSERT_TRUE(wait_until([&] { return (*pub)->stats().paths_held == 1; }, 5.0));
  // ... and a newer one replaces it
  msg::PathSample& fresh = (*pub)->path().back();
  fill_path(fresh, 2, 4);
  fresh.stamp_ns = msg::now_stamp_ns();
  (*pub)->path().publish();
  ASSERT_TRUE(wait_until(
      [&] {
        collect();
        return !seen.empty();
      },
      5.0));
  EXPECT_EQ(seen, std::vector<std::uint64_t>{2});

  // with no newer one, the kept path goes out when the wait is over
  std::this_thread::sleep_for(std::chrono::milliseconds(30));  // past the path interval
  msg::PathSample& alone = (*pub)->path().back();
  fill_path(alone, 3, 4);
  alone.stamp_ns = msg::now_stamp_ns() - 10000000;
  (*pub)->path().publish();
  // (the publisher counts a path once its write returns: a subscriber may
  // have it before that)
  ASSERT_TRUE(wait_until(
      [&] {
        collect();
        return seen.size() == 2 && (*pub)->stats().paths == 2;
      },
      5.0));
  EXPECT_EQ(seen.back(), 3u);
  EXPECT_EQ((*pub)->stats().paths_held, 2u);
}

// A producer that hands off less often than the wait (events, or the
// executive's 50 Hz paths) is not waited for: a path that is already old goes
// out at once instead of after path_refresh_wait_s.
TEST(LivePublisher, AStalePathFromASlowProducerGoesOutAtOnce) {
  PathWatch w;
  ASSERT_NO_FATAL_FAILURE(w.start(0.01));
  std::unique_ptr<LivePublisher>* pub = &w.pub;
  std::vector<std::uint64_t>& seen = w.seen;
  const auto collect = [&] { w.collect(); };
  // paths 1 and 2, 60 ms apart: a producer period of 60 ms, over the 10 ms wait
  for (std::uint64_t seq : {1u, 2u}) {
    msg::PathSample& s = (*pub)->path().back();
    fill_path(s, seq, 4);
    s.stamp_ns = msg::now_stamp_ns();
    (*pub)->path().publish();
    ASSERT_TRUE(wait_until(
        [&] {
          collect();
          return seen.size() == seq;
        },
        5.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
  }
  // path 3, stamped 5 ms before its hand-off: stale, but nothing newer is due
  // (path 1 may have been held: a late first poll finds it stale with no
  // producer period known yet)
  const std::uint64_t held_before = (*pub)->stats().paths_held;
  msg::PathSample& late = (*pub)->path().back();
  fill_path(late, 3, 4);
  late.stamp_ns = msg::now_stamp_ns() - 5000000;
  (*pub)->path().publish();
  ASSERT_TRUE(wait_until(
      [&] {
        collect();
        return seen.size() == 3;
      },
      5.0));
  EXPECT_EQ(seen, (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ((*pub)->stats().paths_held, held_before);
}

TEST(LivePublisher, ThumbnailAtMostOncePerIntervalAndTheLastOnStop) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  QosPtr qos = reader_qos(Topic::thumbnail);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  Result<Reader> reader = Reader::create(*p, Topic::thumbnail, qos.get());
  ASSERT_TRUE(reader.ok());
  PublisherConfig config;
  config.thumbnail_max_hz = 2.0;
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, config);
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE(reader->wait_for_writers(1, 5.0).ok());
  // 10 renders in 0.5 s: at most 2 pass the rate (t = 0, 0.5 s), the last on stop
  for (std::uint32_t i = 1; i <= 10; ++i) {
    msg::ThumbnailSample& t = (*pub)->thumbnail().back();
    t.stamp_ns = i;
    const std::uint8_t png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::memcpy(t.png, png, 8);
    t.png[8] = static_cast<std::uint8_t>(i);
    t.png_size_bytes = 9;
    (*pub)->thumbnail().publish();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE((*pub)->stop().ok());
  std::vector<int> seen;
  wait_until(
      [&] {
        (void)reader->take<sensor_msgs_msg_dds__CompressedImage_>(
            [&](const sensor_msgs_msg_dds__CompressedImage_& m, const dds_sample_info_t&) {
              seen.push_back(m.data._buffer[8]);
            });
        return !seen.empty() && seen.back() == 10;
      },
      5.0);
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), 10);
  EXPECT_LE(seen.size(), 3u);
  EXPECT_EQ((*pub)->stats().thumbnails, seen.size());
}

TEST(LivePublisher, HealthIsBestEffortAndCarriesLayerCounters) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> best_effort = Reader::create(*p, Topic::health);
  QosPtr reliable_qos = reader_qos(Topic::health);
  dds_qset_reliability(reliable_qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  Result<Reader> reliable = Reader::create(*p, Topic::health, reliable_qos.get());
  ASSERT_TRUE(best_effort.ok() && reliable.ok());
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, PublisherConfig{});
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE(best_effort->wait_for_writers(1, 5.0).ok());
  // a reliable reader asks for more than a best-effort writer offers
  EXPECT_FALSE(reliable->wait_for_writers(1, 0.3).ok());

  msg::HealthSample& h = (*pub)->health().back();
  h = msg::HealthSample{};
  h.sequence = 9;
  h.period_us = 1000.0;
  h.wakeup_latency = {2.0, 8.5, 30.0, 55.0, 1000};
  h.overruns = 3;
  h.safe_state = true;
  msg::copy_text(h.safe_state_reason, "device fault");
  (*pub)->health().publish();

  ASSERT_TRUE(*best_effort->wait(5.0));
  int got = 0;
  (void)best_effort->take<visvol_msgs_msg_dds__LoopHealth_>(
      [&](const visvol_msgs_msg_dds__LoopHealth_& m, const dds_sample_info_t&) {
        ++got;
        EXPECT_EQ(m.sequence_number, 9u);
        EXPECT_EQ(m.wakeup_latency.p99_us, 30.0);
        EXPECT_EQ(m.wakeup_latency.count, 1000u);
        EXPECT_EQ(m.overruns, 3u);
        EXPECT_TRUE(m.safe_state);
        EXPECT_STREQ(m.safe_state_reason, "device fault");
        EXPECT_EQ(m.publish_errors, 0u);
      });
  EXPECT_EQ(got, 1);
}

TEST(LivePublisher, BadSampleIsCountedAndTheThreadGoesOn) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> reader = Reader::create(*p, Topic::path_update);
  ASSERT_TRUE(reader.ok());
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, PublisherConfig{});
  ASSERT_TRUE(pub.ok());
  msg::PathSample& bad = (*pub)->path().back();
  fill_path(bad, 1, 3);
  bad.vertex_count = msg::kMaxPathVertices + 1;
  (*pub)->path().publish();
  ASSERT_TRUE(wait_until([&] { return (*pub)->stats().errors == 1; }, 5.0));
  EXPECT_NE((*pub)->stats().last_error.find("vertex_count"), std::string::npos);
  fill_path((*pub)->path().back(), 2, 3);
  (*pub)->path().publish();
  std::vector<msg::PathSample> got = take_updates(*reader, 5.0);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sequence, 2u);
}

TEST(LivePublisher, RejectsBadConfiguration) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  PublisherConfig c;
  c.path_hz = 0.0;
  Result<std::unique_ptr<LivePublisher>> pub = LivePublisher::start(*p, c);
  ASSERT_FALSE(pub.ok());
  EXPECT_NE(pub.status().message().find("path_hz"), std::string::npos);
  c = PublisherConfig{};
  c.idle_poll_interval_s = c.poll_interval_s / 2;
  EXPECT_FALSE(validate(c).ok());
  c = PublisherConfig{};
  c.linger_s = std::nan("");
  EXPECT_FALSE(validate(c).ok());
}

}  // namespace
}  // namespace visvol::dds
