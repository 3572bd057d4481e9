// visvol-console under systemd (a unit of Type=notify, app/systemd/): READY=1
// once the 1 kHz loop runs, WATCHDOG=1 only while the loop's ticks advance and
// the DDS publisher's thread goes on passing (a stalled loop or a dead
// publisher lets systemd's watchdog restart the console), STATUS= lines for
// `systemctl status`, STOPPING=1 when the session ends for good. Through
// libsystemd's sd_notify; without NOTIFY_SOCKET every call does nothing.
//
// Thread-safety: the console's main thread only (sd_notify sends a datagram:
// never the real-time thread).
#pragma once

#include <cstdint>
#include <string>

namespace visvol::app {

// When a WATCHDOG=1 is due: half the watchdog interval after the last one,
// and only if the loop's ticks and the publisher's passes have both moved
// since the previous call (no publisher: its passes are not asked for), so a
// stall stops the pings at once. Call it several times an interval.
class WatchdogGate {
 public:
  explicit WatchdogGate(double interval_s) : half_s_(0.5 * interval_s) {}
  bool due(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes);

 private:
  double half_s_;
  double last_ping_s_ = -1e300;
  std::uint64_t ticks_ = 0, passes_ = 0;  // at the previous call
};

class Supervisor {
 public:
  // Reads NOTIFY_SOCKET and WATCHDOG_USEC (and WATCHDOG_PID, if set).
  Supervisor();

  bool notifying() const { return notifying_; }
  double watchdog_interval_s() const { return watchdog_s_; }
  std::uint64_t pings() const { return pings_; }

  void ready(const std::string& status);
  void status(const std::string& status);
  // From the monitor, at least four times a watchdog interval (monitor_period_s).
  void monitor(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes);
  // How often the monitor should call: 100 ms, or a quarter of the interval.
  double monitor_period_s() const;
  // A terrain switch stops one session's loop and starts another's: the
  // watchdog is widened to `seconds` (WATCHDOG_USEC=) until the next ready().
  void extend_watchdog(double seconds, const std::string& status);
  // After the loop has stopped (the device left at zero force).
  void stopping(const std::string& status);

 private:
  void send(const std::string& message);

  bool notifying_ = false;
  double watchdog_s_ = 0;
  std::uint64_t watchdog_usec_ = 0;  // as the unit gave it
  WatchdogGate gate_{0};
  std::uint64_t pings_ = 0;
};

}  // namespace visvol::app
