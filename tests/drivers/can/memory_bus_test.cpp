#include "drivers/can/memory_bus.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace visvol::can {
namespace {

CanFrame data_frame(std::uint32_t id, std::uint8_t len, std::uint8_t fill) {
  CanFrame f;
  f.id = id;
  f.len = len;
  for (std::uint8_t i = 0; i < len; ++i) f.data[i] = static_cast<std::uint8_t>(fill + i);
  return f;
}

std::vector<CanFrame> receive_all(CanBus& bus) {
  std::vector<CanFrame> out;
  CanFrame batch[4];
  for (;;) {
    const std::size_t n = bus.receive(batch, 4);
    out.insert(out.end(), batch, batch + n);
    if (n < 4) return out;
  }
}

TEST(MemoryBus, FrameReachesEveryOtherEndpointNotTheSender) {
  MemoryBus bus(3, 8);
  bus.set_time_ns(1234);
  ASSERT_EQ(bus.endpoint(0).send(data_frame(0x181, 8, 10)), Errc::ok);
  EXPECT_EQ(bus.endpoint(0).pending(), 0u);
  for (std::size_t i : {1u, 2u}) {
    const auto got = receive_all(bus.endpoint(i));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].id, 0x181u);
    EXPECT_EQ(got[0].len, 8);
    EXPECT_EQ(got[0].data[7], 17);
    EXPECT_EQ(got[0].timestamp_ns, 1234);
  }
  EXPECT_EQ(bus.endpoint(0).counters().sent, 1u);
  EXPECT_EQ(bus.endpoint(1).counters().received, 1u);
}

TEST(MemoryBus, FiltersPassOnlyMatchingStandardDataFrames) {
  MemoryBus bus(2, 16);
  bus.endpoint(1).set_filters({{0x181, 0x7FF}, {0x700, 0x780}}, false);
  CanFrame ext = data_frame(0x181, 1, 0);
  ext.flags = CanFrame::kExtended;
  CanFrame rtr = data_frame(0x181, 0, 0);
  rtr.flags = CanFrame::kRemote;
  CanFrame err;
  err.flags = CanFrame::kError;
  err.id = err::kBusOff;
  for (const CanFrame& f : {data_frame(0x181, 1, 0), data_frame(0x182, 1, 0), data_frame(0x705, 1, 0),
                            data_frame(0x77F, 1, 0), data_frame(0x681, 1, 0), ext, rtr, err}) {
    ASSERT_EQ(bus.endpoint(0).send(f), Errc::ok);
  }
  const auto got = receive_all(bus.endpoint(1));
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].id, 0x181u);
  EXPECT_EQ(got[1].id, 0x705u);
  EXPECT_EQ(got[2].id, 0x77Fu);
}

TEST(MemoryBus, ErrorFramesOnlyWhenEnabledAndCounted) {
  MemoryBus bus(3, 8);
  bus.endpoint(1).set_filters({}, true);
  bus.endpoint(2).set_filters({}, false);
  CanFrame off;
  off.flags = CanFrame::kError;
  off.id = err::kBusOff | err::kController;
  off.len = 8;
  off.data[1] = err::kCtrlTxPassive;
  bus.inject(off);
  const auto got = receive_all(bus.endpoint(1));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].is_error());
  EXPECT_TRUE(classify_error(got[0]).bus_off);
  EXPECT_TRUE(classify_error(got[0]).passive);
  EXPECT_EQ(bus.endpoint(1).counters().bus_off, 1u);
  EXPECT_EQ(bus.endpoint(1).counters().error_frames, 1u);
  EXPECT_TRUE(receive_all(bus.endpoint(2)).empty());
  // inject() reaches every endpoint, including 0.
  EXPECT_EQ(receive_all(bus.endpoint(0)).size(), 1u);
}

TEST(MemoryBus, FullQueueDropsNewFramesAndCountsThem) {
  MemoryBus bus(2, 4);
  for (std::uint8_t i = 0; i < 10; ++i) ASSERT_EQ(bus.endpoint(0).send(data_frame(0x100 + i, 1, i)), Errc::ok);
  EXPECT_EQ(bus.endpoint(1).counters().dropped, 6u);
  const auto got = receive_all(bus.endpoint(1));
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(got[i].id, 0x100u + i) << "oldest frames kept, in order";
}

TEST(MemoryBus, RejectsFramesLongerThanEightBytes) {
  MemoryBus bus(2, 4);
  CanFrame f = data_frame(0x181, 8, 0);
  f.len = 9;
  EXPECT_EQ(bus.endpoint(0).send(f), Errc::invalid_argument);
  EXPECT_EQ(bus.endpoint(0).counters().send_failed, 1u);
  EXPECT_EQ(bus.endpoint(1).pending(), 0u);
}

TEST(Drain, HandsOnEveryPendingFrameUpToTheCap) {
  MemoryBus bus(2, 64);
  for (std::uint8_t i = 0; i < 40; ++i) ASSERT_EQ(bus.endpoint(0).send(data_frame(0x100, 1, i)), Errc::ok);
  CanFrame batch[16];
  std::vector<std::uint8_t> seen;
  bool capped = true;
  EXPECT_EQ(drain(bus.endpoint(1), batch, 256, &capped, [&](const CanFrame& f) { seen.push_back(f.data[0]); }), 40u);
  EXPECT_FALSE(capped);
  ASSERT_EQ(seen.size(), 40u);
  for (std::uint8_t i = 0; i < 40; ++i) EXPECT_EQ(seen[i], i);

  for (std::uint8_t i = 0; i < 40; ++i) ASSERT_EQ(bus.endpoint(0).send(data_frame(0x100, 1, i)), Errc::ok);
  EXPECT_EQ(drain(bus.endpoint(1), batch, 20, &capped, [](const CanFrame&) {}), 20u);
  EXPECT_TRUE(capped);
  EXPECT_EQ(bus.endpoint(1).pending(), 20u) << "the rest waits for the next tick";
}

TEST(ClassifyError, MapsKernelErrorClasses) {
  CanFrame f;
  EXPECT_FALSE(classify_error(f).bus_off) << "a data frame is no error";
  f.flags = CanFrame::kError;
  f.len = 8;
  f.id = err::kRestarted;
  EXPECT_TRUE(classify_error(f).restarted);
  EXPECT_FALSE(classify_error(f).bus_off);
  f.id = err::kProtocol | err::kNoAck;
  EXPECT_TRUE(classify_error(f).bus_error);
  f.id = err::kController;
  f.data[1] = err::kCtrlRxOverflow;
  EXPECT_TRUE(classify_error(f).rx_overflow);
  EXPECT_FALSE(classify_error(f).passive);
  CanCounters counters;
  f.id = err::kBusOff | err::kBusError;
  count_error_frame(counters, f);
  EXPECT_EQ(counters.error_frames, 1u);
  EXPECT_EQ(counters.bus_off, 1u);
  EXPECT_EQ(counters.bus_errors, 1u);
  EXPECT_EQ(counters.restarts, 0u);
}

}  // namespace
}  // namespace visvol::can
