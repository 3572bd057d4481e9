#include "app/supervisor.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace visvol::app {

bool WatchdogGate::due(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes) {
  if (now_s - last_s_ < half_s_) return false;
  const bool moved = !seen_ || (loop_ticks > ticks_ && (!with_publisher || publisher_passes > passes_));
  if (!moved) return false;  // stalled: let systemd's watchdog fire
  seen_ = true;
  last_s_ = now_s;
  ticks_ = loop_ticks;
  passes_ = publisher_passes;
  return true;
}

Supervisor::Supervisor() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  notifying_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  if (notifying_ && sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    watchdog_s_ = static_cast<double>(usec) * 1e-6;
    gate_ = WatchdogGate(watchdog_s_);
  }
}

void Supervisor::send(const std::string& message) {
  if (notifying_) sd_notify(0, message.c_str());
}

void Supervisor::ready(const std::string& status) { send("READY=1\nSTATUS=" + status); }

void Supervisor::status(const std::string& status) { send("STATUS=" + status); }

void Supervisor::monitor(double now_s, std::uint64_t loop_ticks, bool with_publisher, std::uint64_t publisher_passes) {
  if (!notifying_ || watchdog_s_ <= 0) return;
  if (!gate_.due(now_s, loop_ticks, with_publisher, publisher_passes)) return;
  send("WATCHDOG=1");
  ++pings_;
}

void Supervisor::stopping(const std::string& status) { send("STOPPING=1\nSTATUS=" + status); }

}  // namespace visvol::app
