// Fault injection for supervision tests and hardware-in-the-loop rigs (as
// PX4's `failure` command): faults a console must survive or report, made on
// purpose. Off unless an option asks for it.
#pragma once

#include <cstdint>

#include "rt/exec/periodic_loop.hpp"

namespace visvol::app {

// A stalled loop (--inject-stall AT_S FOR_S): the loop thread stops ticking
// `at_s` seconds after its first tick for `for_s` seconds, as a loop stuck on
// a lock or a page would, then goes on. Blocks the real-time thread on
// purpose, once; otherwise it passes every call on to the task it wraps.
class StallingTask final : public rt::PeriodicTask {
 public:
  StallingTask(rt::PeriodicTask& task, double at_s, double for_s);

  void warm_up() override { task_.warm_up(); }
  void tick(const rt::TickTime& time) override;
  void safe_state() override { task_.safe_state(); }
  void stopping() override { task_.stopping(); }

 private:
  rt::PeriodicTask& task_;
  std::int64_t at_ns_, for_ns_;
  std::int64_t first_ns_ = -1;
  bool stalled_ = false;
};

}  // namespace visvol::app
