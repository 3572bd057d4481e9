// The planning console: a field pack mapped within a memory budget, the
// 1 kHz executive (rope, servo, haptic device), DDS publishing and command
// intake, and a monitor that logs loop health and shows progress.
//
//   main thread        start-up, then the monitor (10 Hz): health to DDS and
//                      to the log, a progress line every second
//   loop thread        the executive's ticks (SCHED_FIFO when permitted)
//   pager thread       resident tiles around the rope
//   fitter thread      the rope's path fitted into the vehicle's envelope,
//                      for the publisher and the renderer (flyable_path.hpp)
//   renderer thread    a thumbnail when the rope comes to rest (at most 1 Hz)
//   DDS threads        publisher, command intake, Cyclone's own
//
// Outputs in the output directory (written whole or not at all):
//   path.csv       the last flyable path: x_m, y_m, z_m (pack CRS), F_p, clearance_m
//   health.csv     one line a second: loop timing, F_c, device, tiles, memory
//   summary.json   the run: loop timing percentiles, overruns, faults, memory
//                  against the budget, tiles, commands, the path's figures
//   thumbnail.png  the last thumbnail: the rope where it ended
// A session that ends on a switch-terrain command writes them into
// OUT/session-N-PACKID, and the next session runs on the other pack; if
// that session cannot start (its pack changed on disk since start-up, or
// does not fit the budget), the console goes back to the pack it left
// (session_after_failed_switch) and its summary.json names the failure.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "app/console_options.hpp"
#include "base/status.hpp"

namespace visvol::app {

// The session to run when `failed`, the session a terrain switch asked for,
// could not start with `error`: the pack it switched from, for the time left,
// with the pack that failed no longer one a switch may name, and the failure
// recorded for the summary.
ConsoleOptions session_after_failed_switch(const ConsoleOptions& failed, const std::string& error);

class Console {
 public:
  // Everything reserved and started; errors name the input and the problem
  // (Errc::invalid_argument for bad options or input, others for the system).
  static Result<std::unique_ptr<Console>> start(const ConsoleOptions& options);
  ~Console();

  // Monitors until `stop` is set or the configured time has passed, then
  // stops every thread and writes the outputs. Returns what went wrong
  // writing them, if anything.
  Status run(const std::atomic<bool>& stop);

  // After run(): when it ended on a switch-terrain command, the options of
  // the next session (the same console on that pack, for the time left, the
  // endpoints at the new pack's default); otherwise nothing.
  std::optional<ConsoleOptions> next_session() const;

 private:
  struct Impl;
  explicit Console(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace visvol::app
