// SocketCanBus start-up errors, on any kernel. Its behaviour on a real vcan
// interface is tested in tests/hil (natively where the kernel has vcan, in a
// throw-away VM otherwise).
#include "drivers/can/socketcan_bus.hpp"

#include <gtest/gtest.h>

namespace visvol::can {
namespace {

Status open_error(const SocketCanConfig& config) {
  auto bus = SocketCanBus::open(config);
  EXPECT_FALSE(bus.ok());
  return bus.ok() ? Status() : bus.status();
}

TEST(SocketCanBus, RefusesAMissingInterfaceName) {
  const Status s = open_error(SocketCanConfig{});
  EXPECT_EQ(s.code(), Errc::invalid_argument);
  EXPECT_NE(s.message().find("no name"), std::string::npos) << s.message();
}

TEST(SocketCanBus, RefusesAnOverlongInterfaceName) {
  SocketCanConfig c;
  c.interface = "vcan-far-too-long-name";
  const Status s = open_error(c);
  EXPECT_EQ(s.code(), Errc::invalid_argument);
  EXPECT_NE(s.message().find("vcan-far-too-long-name"), std::string::npos) << s.message();
}

TEST(SocketCanBus, RefusesMoreFiltersThanTheKernelTakes) {
  SocketCanConfig c;
  c.interface = "vcan0";
  c.filters.resize(513);
  const Status s = open_error(c);
  EXPECT_EQ(s.code(), Errc::invalid_argument);
  EXPECT_NE(s.message().find("513 filters"), std::string::npos) << s.message();
}

TEST(SocketCanBus, NamesTheInterfaceAndTheCauseWhenItCannotOpen) {
  for (const char* name : {"visvolnone0", "lo"}) {
    SocketCanConfig c;
    c.interface = name;
    const Status s = open_error(c);
    EXPECT_NE(s.message().find(std::string("'") + name + "'"), std::string::npos) << s.message();
    // No SocketCAN in this kernel, no such interface, or not a CAN interface.
    const bool explained = s.message().find("no SocketCAN") != std::string::npos ||
                           s.message().find("no such network interface") != std::string::npos ||
                           s.message().find("not a CAN interface") != std::string::npos;
    EXPECT_TRUE(explained) << s.message();
  }
}

}  // namespace
}  // namespace visvol::can
