#include "app/supervisor.hpp"

#include <systemd/sd-daemon.h>

#include <algorithm>
#include <cstdlib>

namespace visvol::app {

bool WatchdogGate::due(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes) {
  const bool moved = loop_ticks > ticks_ && (!with_publisher || publisher_passes > passes_);
  ticks_ = loop_ticks;
  passes_ = publisher_passes;
  if (!moved) return false;  // stalled since the last look: let systemd's watchdog fire
  if (now_s - last_ping_s_ < half_s_ - 1e-9) return false;
  last_ping_s_ = now_s;
  return true;
}

Supervisor::Supervisor() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  notifying_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  if (notifying_ && sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    watchdog_usec_ = usec;
    watchdog_s_ = static_cast<double>(usec) * 1e-6;
    gate_ = WatchdogGate(watchdog_s_);
  }
}

void Supervisor::send(const std::string& message) {
  if (notifying_) sd_notify(0, message.c_str());
}

void Supervisor::ready(const std::string& status) {
  std::string m = "READY=1\nSTATUS=" + status;
  if (watchdog_s_ > 0) {  // the interval the unit set (a terrain switch may have widened it)
    m += "\nWATCHDOG_USEC=" + std::to_string(watchdog_usec_);
  }
  send(m);
}

double Supervisor::monitor_period_s() const { return watchdog_s_ > 0 ? std::min(0.1, 0.25 * watchdog_s_) : 0.1; }

void Supervisor::extend_watchdog(double seconds, const std::string& status) {
  std::string m = "STATUS=" + status;
  if (watchdog_s_ > 0) m += "\nWATCHDOG=1\nWATCHDOG_USEC=" + std::to_string(static_cast<long long>(seconds * 1e6));
  send(m);
}

void Supervisor::status(const std::string& status) { send("STATUS=" + status); }

void Supervisor::monitor(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes) {
  if (!notifying_ || watchdog_s_ <= 0) return;
  if (!gate_.due(now_s, loop_ticks, with_publisher, publisher_passes)) return;
  send("WATCHDOG=1");
  ++pings_;
}

void Supervisor::stopping(const std::string& status) { send("STOPPING=1\nSTATUS=" + status); }

}  // namespace visvol::app
