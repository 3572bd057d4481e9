// The console's systemd supervision: when WATCHDOG=1 is due (only while the
// loop and the publisher move), and the datagrams sd_notify sends to a socket
// that plays systemd.
#include "app/supervisor.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace visvol::app {
namespace {

TEST(WatchdogGate, PingsEveryHalfIntervalWhileBothMove) {
  WatchdogGate g(1.0);
  std::uint64_t ticks = 100, passes = 10;
  int pings = 0;
  for (int k = 0; k <= 30; ++k) {  // 3 s in 0.1 s steps
    ticks += 100;
    passes += 20;
    pings += g.due(0.1 * k, ticks, true, passes);
  }
  EXPECT_GE(pings, 6);
  EXPECT_LE(pings, 7);
}

TEST(WatchdogGate, AStallStopsThePingsAtOnce) {
  WatchdogGate g(1.0);
  EXPECT_TRUE(g.due(0.0, 100, false, 0));
  EXPECT_FALSE(g.due(0.4, 200, false, 0)) << "too soon";
  EXPECT_FALSE(g.due(0.5, 200, false, 0)) << "no tick since the last look, though the last ping saw fewer";
  EXPECT_TRUE(g.due(0.6, 201, false, 0));
}

TEST(WatchdogGate, NoTickYetNoPing) {
  WatchdogGate g(1.0);
  EXPECT_FALSE(g.due(0.0, 0, false, 0));
  EXPECT_TRUE(g.due(0.1, 1, false, 0));
}

TEST(WatchdogGate, AStalledLoopOrPublisherStopsThePings) {
  WatchdogGate g(1.0);
  EXPECT_TRUE(g.due(0.0, 100, true, 10));
  EXPECT_FALSE(g.due(0.6, 100, true, 30)) << "the loop's ticks did not move";
  EXPECT_FALSE(g.due(1.2, 900, true, 10)) << "the publisher's passes did not move";
  EXPECT_FALSE(g.due(1.3, 100, false, 10)) << "still the same ticks";
  EXPECT_TRUE(g.due(1.4, 901, false, 10)) << "no publisher: the loop alone";
  EXPECT_FALSE(g.due(1.5, 902, false, 10)) << "too soon after the last";
}

// A datagram socket where systemd's would be.
class FakeSystemd {
 public:
  FakeSystemd() {
    path_ = ::testing::TempDir() + "/notify_" + std::to_string(getpid()) + ".sock";
    unlink(path_.c_str());
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    path_.copy(a.sun_path, sizeof a.sun_path - 1);
    bound_ = fd_ >= 0 && bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  }
  ~FakeSystemd() {
    if (fd_ >= 0) close(fd_);
    unlink(path_.c_str());
  }
  bool bound() const { return bound_; }
  const std::string& path() const { return path_; }
  std::vector<std::string> received() {
    std::vector<std::string> out;
    char buf[4096];
    for (;;) {
      const ssize_t n = recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) break;
      out.emplace_back(buf, static_cast<std::size_t>(n));
    }
    return out;
  }

 private:
  std::string path_;
  int fd_ = -1;
  bool bound_ = false;
};

TEST(Supervisor, SaysReadyPingsAndStopping) {
  FakeSystemd systemd;
  ASSERT_TRUE(systemd.bound());
  setenv("NOTIFY_SOCKET", systemd.path().c_str(), 1);
  setenv("WATCHDOG_USEC", "400000", 1);
  unsetenv("WATCHDOG_PID");
  Supervisor s;  // sd_notify reads NOTIFY_SOCKET at every call: left set until the end
  ASSERT_TRUE(s.notifying());
  EXPECT_DOUBLE_EQ(s.watchdog_interval_s(), 0.4);
  s.ready("pack: rope of 32 segments, hide");
  for (int k = 0; k < 10; ++k) s.monitor(0.1 * k, 100u + static_cast<std::uint64_t>(k), false, 0);
  s.status("pack: F_c 0.01");
  s.extend_watchdog(120.0, "switching terrain to other");
  s.stopping("pack: stopping");
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  const std::vector<std::string> got = systemd.received();
  ASSERT_GE(got.size(), 4u);
  EXPECT_EQ(got.front(), "READY=1\nSTATUS=pack: rope of 32 segments, hide\nWATCHDOG_USEC=400000");
  EXPECT_EQ(got.back(), "STOPPING=1\nSTATUS=pack: stopping");
  int pings = 0;
  for (const std::string& m : got) pings += m == "WATCHDOG=1";
  EXPECT_EQ(pings, 5);  // at 0, 0.2, 0.4, 0.6, 0.8 s
  EXPECT_EQ(s.pings(), 5u);
  EXPECT_EQ(got[got.size() - 2], "STATUS=switching terrain to other\nWATCHDOG=1\nWATCHDOG_USEC=120000000");
  EXPECT_DOUBLE_EQ(s.monitor_period_s(), 0.1);
}

TEST(Supervisor, WithoutSystemdNothingIsSent) {
  unsetenv("NOTIFY_SOCKET");
  Supervisor s;
  EXPECT_FALSE(s.notifying());
  s.ready("x");
  s.monitor(1.0, 10, false, 0);
  EXPECT_EQ(s.pings(), 0u);
}

}  // namespace
}  // namespace visvol::app
