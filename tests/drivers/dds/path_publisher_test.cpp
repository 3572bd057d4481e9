// The path publisher, and the bytes it puts on the wire, with real Cyclone
// participants (domain 212, loopback).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "dds_test_support.hpp"
#include "drivers/dds/path_publisher.hpp"
#include "drivers/dds/topics.hpp"
#include "test_domains.hpp"

namespace visvol::dds {
namespace {

using test::fill_path;
using test::loopback;
using test::make_participant;
using test::make_path;
using test::wait_until;
constexpr std::uint32_t kDomain = test::kDomainPathPublisher;

// Path publisher -----------------------------------------------------------------

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

TEST(PathPublisher, PathAndUpdateArriveWithTheSameHeader) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> path_reader = Reader::create(*p, Topic::path);
  Result<Reader> update_reader = Reader::create(*p, Topic::path_update);
  ASSERT_TRUE(path_reader.ok() && update_reader.ok());
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok()) << pub.status().message();
  ASSERT_TRUE((*pub)->wait_for_subscribers(1, 5.0).ok());

  const auto sample = make_path(7, 5);
  ASSERT_TRUE((*pub)->publish(*sample).ok());

  std::vector<msg::PathSample> updates = take_updates(*update_reader, 5.0);
  ASSERT_EQ(updates.size(), 1u);
  const msg::PathSample& u = updates[0];
  EXPECT_EQ(u.sequence, 7u);
  EXPECT_EQ(u.stamp_ns, sample->stamp_ns);
  EXPECT_EQ(msg::text_of(u.pack_id), "sf_north");
  EXPECT_EQ(u.objective, msg::Objective::hide);
  EXPECT_EQ(u.f_c, sample->f_c);
  EXPECT_EQ(u.vertex_count, 5u);
  for (std::uint32_t i = 0; i < 5; ++i) {
    EXPECT_EQ(u.vertices[i].position.x_m, sample->vertices[i].position.x_m);
    EXPECT_EQ(u.vertices[i].visibility, sample->vertices[i].visibility);
    EXPECT_EQ(u.vertices[i].clearance_m, sample->vertices[i].clearance_m);
  }

  ASSERT_TRUE(*path_reader->wait(5.0));
  int paths = 0;
  (void)path_reader->take<nav_msgs_msg_dds__Path_>([&](const nav_msgs_msg_dds__Path_& msg, const dds_sample_info_t&) {
    ++paths;
    EXPECT_STREQ(msg.header.frame_id, kDefaultFrameId);
    EXPECT_EQ(from_ros_time(msg.header.stamp), sample->stamp_ns);
    ASSERT_EQ(msg.poses._length, 5u);
    for (std::uint32_t i = 0; i < 5; ++i) {
      const auto& pose = msg.poses._buffer[i];
      EXPECT_STREQ(pose.header.frame_id, kDefaultFrameId);
      EXPECT_EQ(pose.pose.position.x, sample->vertices[i].position.x_m);
      EXPECT_EQ(pose.pose.position.z, sample->vertices[i].position.z_m);
      EXPECT_EQ(pose.pose.orientation.w, 1.0);  // identity, not C's zero
    }
  });
  EXPECT_EQ(paths, 1);
}

TEST(PathPublisher, LateJoinerGetsOnlyTheLatestPath) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());
  for (std::uint64_t seq = 1; seq <= 3; ++seq) {
    ASSERT_TRUE((*pub)->publish(*make_path(seq, 4)).ok());
  }
  // joins after the fact
  Result<Reader> late = Reader::create(*p, Topic::path_update);
  ASSERT_TRUE(late.ok());
  std::vector<msg::PathSample> got = take_updates(*late, 5.0);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sequence, 3u);
}

TEST(PathPublisher, VolatileReaderAsRvizUsesMatchesAndGetsNewPathsOnly) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE((*pub)->publish(*make_path(1, 3)).ok());
  QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  Result<Reader> rviz = Reader::create(*p, Topic::path_update, qos.get());
  ASSERT_TRUE(rviz.ok());
  ASSERT_TRUE(rviz->wait_for_writers(1, 5.0).ok());
  EXPECT_TRUE(take_updates(*rviz, 0.2).empty());  // no history for a volatile reader
  ASSERT_TRUE((*pub)->publish(*make_path(2, 3)).ok());
  std::vector<msg::PathSample> got = take_updates(*rviz, 5.0);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sequence, 2u);
}

TEST(PathPublisher, ThumbnailAndTerrainArrive) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());

  auto thumb = std::make_unique<msg::ThumbnailSample>();
  *thumb = msg::ThumbnailSample{};
  const std::uint8_t png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  thumb->png_size_bytes = 100000;
  std::memcpy(thumb->png, png, sizeof png);
  for (std::uint32_t i = 8; i < thumb->png_size_bytes; ++i) {
    thumb->png[i] = static_cast<std::uint8_t>(i * 7);
  }
  thumb->stamp_ns = 42;
  ASSERT_TRUE((*pub)->publish(*thumb).ok());
  thumb->png[0] = 0;
  EXPECT_FALSE((*pub)->publish(*thumb).ok());  // not a PNG: refused, not sent
  thumb->png[0] = 0x89;

  auto terrain = std::make_unique<msg::TerrainInfo>();
  *terrain = msg::TerrainInfo{};
  msg::copy_text(terrain->pack_id, "sf_north");
  msg::copy_text(terrain->crs, "EPSG:32610");
  terrain->min = {540000.0, 4180000.0, -10.0};
  terrain->max = {551100.0, 4194000.0, 600.0};
  terrain->post_spacing_m = 30.0;
  ASSERT_TRUE((*pub)->publish(*terrain).ok());

  // late joiners of both
  Result<Reader> thumb_reader = Reader::create(*p, Topic::thumbnail);
  Result<Reader> terrain_reader = Reader::create(*p, Topic::terrain);
  ASSERT_TRUE(thumb_reader.ok() && terrain_reader.ok());
  ASSERT_TRUE(*thumb_reader->wait(5.0));
  int thumbs = 0;
  (void)thumb_reader->take<sensor_msgs_msg_dds__CompressedImage_>(
      [&](const sensor_msgs_msg_dds__CompressedImage_& msg, const dds_sample_info_t&) {
        ++thumbs;
        EXPECT_STREQ(msg.format, "png");
        ASSERT_EQ(msg.data._length, thumb->png_size_bytes);
        EXPECT_EQ(std::memcmp(msg.data._buffer, thumb->png, thumb->png_size_bytes), 0);
      });
  EXPECT_EQ(thumbs, 1);
  ASSERT_TRUE(*terrain_reader->wait(5.0));
  int terrains = 0;
  (void)terrain_reader->take<visvol_msgs_msg_dds__TerrainInfo_>(
      [&](const visvol_msgs_msg_dds__TerrainInfo_& msg, const dds_sample_info_t&) {
        ++terrains;
        EXPECT_STREQ(msg.crs, "EPSG:32610");
        EXPECT_STREQ(msg.header.frame_id, kDefaultFrameId);
        EXPECT_EQ(msg.max_m.x, 551100.0);
      });
  EXPECT_EQ(terrains, 1);
}

TEST(PathPublisher, WaitForDeliveryWithoutSubscribersReturnsAtOnce) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());
  ASSERT_TRUE((*pub)->publish(*make_path(1, 2)).ok());
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE((*pub)->wait_for_delivery(5.0).ok());
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(1));
  const Status none = (*pub)->wait_for_subscribers(1, 0.05);
  EXPECT_EQ(none.code(), Errc::timeout);
  EXPECT_NE(none.message().find("0 of 1 subscribers"), std::string::npos) << none.message();
}

// The wire format -----------------------------------------------------------------

std::vector<std::uint8_t> take_serialized_path(const Reader& reader) {
  std::vector<std::uint8_t> bytes;
  wait_until(
      [&] {
        Result<std::vector<std::uint8_t>> b = reader.take_serialized();
        if (b.ok() && !b->empty()) bytes = *b;
        return !bytes.empty();
      },
      5.0);
  return bytes;
}

TEST(WireFormat, SmallPathIsPlainCdrByHand) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> reader = Reader::create(*p, Topic::path);
  ASSERT_TRUE(reader.ok());
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p, "w");
  ASSERT_TRUE(pub.ok());
  auto s = std::make_unique<msg::PathSample>();
  *s = msg::PathSample{};
  s->stamp_ns = 1000000002;  // sec 1, nanosec 2
  s->vertex_count = 1;
  s->vertices[0].position = {1.5, -2.0, 3.25};
  ASSERT_TRUE((*pub)->publish(*s).ok());

  // nav_msgs/Path {header {stamp {1, 2}, "w"}, poses [{header {stamp, "w"},
  // pose {position {1.5, -2, 3.25}, orientation {0, 0, 0, 1}}}]}; offsets
  // below count from the end of the encapsulation header.
  const std::vector<std::uint8_t> expected = {
      0x00, 0x01, 0x00, 0x00,                          // CDR_LE, options 0
      0x01, 0x00, 0x00, 0x00,                          //  0 header.stamp.sec = 1
      0x02, 0x00, 0x00, 0x00,                          //  4 header.stamp.nanosec = 2
      0x02, 0x00, 0x00, 0x00, 'w',  0x00,              //  8 header.frame_id = "w"
      0x00, 0x00,                                      // 14 pad to 4
      0x01, 0x00, 0x00, 0x00,                          // 16 poses: 1 element
      0x01, 0x00, 0x00, 0x00,                          // 20 poses[0].header.stamp.sec
      0x02, 0x00, 0x00, 0x00,                          // 24 nanosec
      0x02, 0x00, 0x00, 0x00, 'w',  0x00,              // 28 frame_id = "w"
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00,              // 34 pad to 8 (XCDR1 aligns doubles to 8)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf8, 0x3f,  // 40 position.x = 1.5
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xc0,  // 48 position.y = -2
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0a, 0x40,  // 56 position.z = 3.25
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 64 orientation.x = 0
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 72 orientation.y = 0
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 80 orientation.z = 0
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f,  // 88 orientation.w = 1
  };
  EXPECT_EQ(take_serialized_path(*reader), expected);
}

TEST(WireFormat, LongerPathFollowsTheRules) {
  auto p = make_participant(loopback(kDomain));
  ASSERT_NE(p, nullptr);
  Result<Reader> reader = Reader::create(*p, Topic::path);
  ASSERT_TRUE(reader.ok());
  Result<std::unique_ptr<PathPublisher>> pub = PathPublisher::create(*p);
  ASSERT_TRUE(pub.ok());
  const auto s = make_path(3, 4);
  ASSERT_TRUE((*pub)->publish(*s).ok());

  EXPECT_EQ(take_serialized_path(*reader), test::path_cdr(*s, kDefaultFrameId));
}

}  // namespace
}  // namespace visvol::dds
