// Samples into DDS messages and back, without DDS.
#include "drivers/dds/message_codec.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace visvol::dds {
namespace {

std::unique_ptr<msg::PathSample> path(std::uint32_t n) {
  auto s = std::make_unique<msg::PathSample>();
  *s = msg::PathSample{};
  s->sequence = 12;
  s->stamp_ns = 1700000000500000000LL;
  msg::copy_text(s->pack_id, "sf_north");
  s->objective = msg::Objective::show;
  s->converged = true;
  s->inside_envelope = true;
  s->f_c = 3.5;
  s->length_m = 1234.5;
  s->min_clearance_m = 20.0;
  s->mode = msg::InteractionMode::spool;
  s->spool_paid_out_m = 861.5;
  s->vertex_count = n;
  for (std::uint32_t i = 0; i < n; ++i) {
    s->vertices[i] = {{1.0 * i, 2.0 * i, 3.0 * i}, 0.01 * i, 20.0 + i};
  }
  return s;
}

TEST(RosTime, SplitsIntoSecondsAndNanoseconds) {
  builtin_interfaces_msg_dds__Time_ t = to_ros_time(1700000000123456789LL);
  EXPECT_EQ(t.sec, 1700000000);
  EXPECT_EQ(t.nanosec, 123456789u);
  EXPECT_EQ(from_ros_time(t), 1700000000123456789LL);
  t = to_ros_time(-1);  // before the epoch: nanosec stays positive
  EXPECT_EQ(t.sec, -1);
  EXPECT_EQ(t.nanosec, 999999999u);
  EXPECT_EQ(from_ros_time(t), -1);
  t = to_ros_time(INT64_MAX);  // past 2038: clamped
  EXPECT_EQ(t.sec, INT32_MAX);
  EXPECT_GT(msg::now_stamp_ns(), 1600000000LL * 1000000000LL);
}

TEST(PathMessages, FillsRosPathAndUpdateWithOneHeader) {
  auto m = std::make_unique<PathMessages>("visvol_world");
  const auto s = path(3);
  ASSERT_TRUE(m->fill(*s).ok());
  const nav_msgs_msg_dds__Path_& p = m->path();
  EXPECT_STREQ(p.header.frame_id, "visvol_world");
  EXPECT_EQ(from_ros_time(p.header.stamp), s->stamp_ns);
  ASSERT_EQ(p.poses._length, 3u);
  for (std::uint32_t i = 0; i < 3; ++i) {
    const auto& pose = p.poses._buffer[i];
    EXPECT_STREQ(pose.header.frame_id, "visvol_world");
    EXPECT_EQ(from_ros_time(pose.header.stamp), s->stamp_ns);
    EXPECT_EQ(pose.pose.position.y, 2.0 * i);
    EXPECT_EQ(pose.pose.orientation.x, 0.0);
    EXPECT_EQ(pose.pose.orientation.w, 1.0);
  }
  const visvol_msgs_msg_dds__PathUpdate_& u = m->update();
  EXPECT_EQ(u.sequence_number, 12u);
  EXPECT_STREQ(u.pack_id, "sf_north");
  EXPECT_EQ(u.objective, 2);
  EXPECT_TRUE(u.converged);
  EXPECT_TRUE(u.inside_envelope);
  EXPECT_EQ(u.length_m, 1234.5);
  ASSERT_EQ(u.positions_m._length, 3u);
  ASSERT_EQ(u.visibility._length, 3u);
  ASSERT_EQ(u.clearance_m._length, 3u);
  EXPECT_EQ(u.clearance_m._buffer[2], 22.0);

  // a shorter path afterwards publishes only its own vertices
  ASSERT_TRUE(m->fill(*path(1)).ok());
  EXPECT_EQ(m->path().poses._length, 1u);
  EXPECT_EQ(m->update().visibility._length, 1u);
}

TEST(PathMessages, RefusesMoreVerticesThanReserved) {
  auto m = std::make_unique<PathMessages>("visvol_world");
  auto s = path(2);
  s->vertex_count = msg::kMaxPathVertices + 1;
  const Status st = m->fill(*s);
  EXPECT_EQ(st.code(), Errc::invalid_argument);
  EXPECT_NE(st.message().find("vertex_count 513"), std::string::npos) << st.message();
  s->vertex_count = msg::kMaxPathVertices;  // the full capacity is fine
  EXPECT_TRUE(m->fill(*s).ok());
}

TEST(PathMessages, UnterminatedPackIdIsCutNotOverrun) {
  auto m = std::make_unique<PathMessages>("visvol_world");
  auto s = path(1);
  std::memset(s->pack_id, 'x', sizeof s->pack_id);  // no NUL at all
  ASSERT_TRUE(m->fill(*s).ok());
  EXPECT_EQ(std::strlen(m->update().pack_id), msg::kPackIdCapacity - 1);
}

TEST(DecodePathUpdate, RoundTripAndInconsistentLengths) {
  auto m = std::make_unique<PathMessages>("visvol_world");
  const auto s = path(4);
  ASSERT_TRUE(m->fill(*s).ok());
  auto back = std::make_unique<msg::PathSample>();
  ASSERT_TRUE(decode_path_update(m->update(), *back).ok());
  EXPECT_EQ(back->sequence, s->sequence);
  EXPECT_EQ(back->stamp_ns, s->stamp_ns);
  EXPECT_EQ(back->objective, s->objective);
  EXPECT_TRUE(back->inside_envelope);
  EXPECT_EQ(back->mode, msg::InteractionMode::spool);
  EXPECT_EQ(back->spool_paid_out_m, 861.5);
  EXPECT_EQ(back->vertex_count, 4u);
  EXPECT_EQ(std::memcmp(back->vertices, s->vertices, 4 * sizeof(msg::PathVertex)), 0);

  visvol_msgs_msg_dds__PathUpdate_ broken = m->update();
  broken.visibility._length = 3;
  EXPECT_NE(decode_path_update(broken, *back).message().find("4 positions but 3 visibility"), std::string::npos);
  visvol_msgs_msg_dds__PathUpdate_ bad_mode = m->update();
  bad_mode.mode = 3;
  EXPECT_EQ(decode_path_update(bad_mode, *back).message(), "path update: mode 3 is not known (1 pull, 2 spool)");
}

TEST(ThumbnailMessage, ChecksTheBytesArePng) {
  auto t = std::make_unique<msg::ThumbnailSample>();
  *t = msg::ThumbnailSample{};
  ThumbnailMessage m("visvol_world");
  EXPECT_NE(m.fill(*t).message().find("png_size_bytes 0"), std::string::npos);
  t->png_size_bytes = msg::kMaxThumbnailBytes + 1;
  EXPECT_FALSE(m.fill(*t).ok());
  t->png_size_bytes = 16;
  EXPECT_NE(m.fill(*t).message().find("PNG signature"), std::string::npos);
  const std::uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::memcpy(t->png, sig, 8);
  ASSERT_TRUE(m.fill(*t).ok());
  EXPECT_STREQ(m.message().format, "png");
  EXPECT_EQ(m.message().data._length, 16u);
  EXPECT_EQ(m.message().data._buffer, t->png);  // no copy
}

TEST(TerrainMessage, NeedsAPackAndACrs) {
  auto info = std::make_unique<msg::TerrainInfo>();
  *info = msg::TerrainInfo{};
  TerrainMessage m("visvol_world");
  EXPECT_NE(m.fill(*info).message().find("empty pack_id"), std::string::npos);
  msg::copy_text(info->pack_id, "sf_north");
  EXPECT_NE(m.fill(*info).message().find("neither crs nor crs_wkt"), std::string::npos);
  msg::copy_text(info->crs_wkt, "PROJCRS[\"WGS 84 / UTM zone 10N\"]");
  ASSERT_TRUE(m.fill(*info).ok());
  EXPECT_STREQ(m.message().crs, "");
  EXPECT_STREQ(m.message().crs_wkt, "PROJCRS[\"WGS 84 / UTM zone 10N\"]");
}

TEST(CatalogueMessage, RoundTripsEveryEntryAndRefusesWhatItCannotSay) {
  auto c = std::make_unique<msg::TerrainCatalogue>();
  *c = msg::TerrainCatalogue{};
  c->stamp_ns = 1'700'000'000'123'456'789;
  c->count = 2;
  msg::copy_text(c->entries[0].pack_id, "sf_north");
  msg::copy_text(c->entries[0].crs, "EPSG:32610");
  msg::copy_text(c->entries[0].name, "sf_north_utm10_30m.tif");
  msg::copy_text(c->entries[0].build, "{\"range_posts\":64}");
  c->entries[0].state = msg::CatalogueState::verified;
  c->entries[0].levels = 3;
  c->entries[0].post_spacing_m = 30.0;
  c->entries[0].planning_min = {545000, 4180000, 0};
  c->entries[0].planning_max = {555000, 4190000, 0};
  msg::copy_text(c->entries[1].pack_id, "taunus");
  msg::copy_text(c->entries[1].reason, "tile 3 of level 0: checksum");
  c->entries[1].state = msg::CatalogueState::refused;
  CatalogueMessage m("visvol_world");
  ASSERT_TRUE(m.fill(*c).ok());
  EXPECT_EQ(m.message().entries._length, 2u);
  EXPECT_STREQ(m.message().entries._buffer[1].reason, "tile 3 of level 0: checksum");
  auto back = std::make_unique<msg::TerrainCatalogue>();
  ASSERT_TRUE(decode_catalogue(m.message(), *back).ok());
  EXPECT_EQ(back->stamp_ns, c->stamp_ns);
  ASSERT_EQ(back->count, 2u);
  EXPECT_EQ(msg::text_of(back->entries[0].pack_id), "sf_north");
  EXPECT_EQ(msg::text_of(back->entries[0].build), "{\"range_posts\":64}");
  EXPECT_EQ(back->entries[0].state, msg::CatalogueState::verified);
  EXPECT_EQ(back->entries[0].levels, 3u);
  EXPECT_EQ(back->entries[0].planning_max.y_m, 4190000.0);
  EXPECT_EQ(back->entries[1].state, msg::CatalogueState::refused);
  EXPECT_EQ(msg::text_of(back->entries[1].reason), "tile 3 of level 0: checksum");

  c->entries[1].pack_id[0] = '\0';
  EXPECT_NE(m.fill(*c).message().find("without a pack id"), std::string::npos);
  c->count = static_cast<std::uint32_t>(msg::kMaxCatalogueEntries + 1);
  EXPECT_NE(m.fill(*c).message().find("at most 64"), std::string::npos);
  // a state no CATALOGUE_* names, from the wire
  c->count = 1;
  ASSERT_TRUE(m.fill(*c).ok());
  visvol_msgs_msg_dds__TerrainCatalogue_ wire = m.message();
  visvol_msgs_msg_dds__TerrainCatalogueEntry_ odd = wire.entries._buffer[0];
  odd.state = 7;
  wire.entries._buffer = &odd;
  EXPECT_NE(decode_catalogue(wire, *back).message().find("state 7"), std::string::npos);
}

TEST(HealthMessage, AddsTheLayerCounters) {
  msg::HealthSample h{};
  h.sequence = 3;
  h.compute_time = {10.0, 20.0, 40.0, 80.0, 100};
  h.misses = 2;
  LayerCounters c;
  c.commands_accepted = 4;
  c.commands_rejected = 5;
  c.publish_errors = 6;
  HealthMessage m("visvol_world");
  ASSERT_TRUE(m.fill(h, c).ok());
  EXPECT_EQ(m.message().compute_time.max_us, 80.0);
  EXPECT_EQ(m.message().misses, 2u);
  EXPECT_EQ(m.message().commands_accepted, 4u);
  EXPECT_EQ(m.message().commands_rejected, 5u);
  EXPECT_EQ(m.message().publish_errors, 6u);
  EXPECT_STREQ(m.message().safe_state_reason, "");
}

TEST(DeviceStatusMessage, CopiesEveryField) {
  msg::DeviceStatusSample d{};
  d.sequence = 8;
  msg::copy_text(d.device, "phantom-1");
  d.state = msg::DeviceState::fault;
  d.fault_bits = 0x21;
  d.motor_temperature_c = 61.5;
  d.can_errors = 3;
  d.bus_off_count = 1;
  DeviceStatusMessage m("visvol_world");
  ASSERT_TRUE(m.fill(d).ok());
  EXPECT_STREQ(m.message().device, "phantom-1");
  EXPECT_EQ(m.message().state, 4);
  EXPECT_EQ(m.message().fault_bits, 0x21u);
  EXPECT_EQ(m.message().motor_temperature_c, 61.5);
  EXPECT_EQ(m.message().bus_off_count, 1u);
}

TEST(Samples, NamesOfEnumerations) {
  EXPECT_STREQ(to_string(msg::Objective::hide), "hide");
  EXPECT_STREQ(to_string(msg::RopeModel::articulated), "articulated");
  EXPECT_STREQ(to_string(msg::CommandKind::set_segment_count), "set-segments");
  EXPECT_STREQ(to_string(msg::AckResult::failed), "failed");
  EXPECT_STREQ(to_string(msg::DeviceState::idle), "idle");
  EXPECT_STREQ(to_string(msg::CatalogueState::refused), "refused");
  EXPECT_EQ(to_string(static_cast<msg::CommandKind>(0)), nullptr);
  EXPECT_EQ(to_string(static_cast<msg::CatalogueState>(3)), nullptr);
  char small[4];
  EXPECT_FALSE(msg::copy_text(small, "abcdef"));
  EXPECT_STREQ(small, "abc");
  EXPECT_TRUE(msg::copy_text(small, "ab"));
  EXPECT_EQ(msg::text_of(small), "ab");
}

}  // namespace
}  // namespace visvol::dds
