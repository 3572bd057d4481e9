// Operator scripts for the simulated device: timed hand motions, button
// presses and fault injections, read from a text file.
//
// One event per line, `TIME ACTION [ARGS]`, TIME in seconds from the start of
// the simulation, non-decreasing; distances in device millimetres (x right,
// y up, z toward the operator); `#` starts a comment.
//
//   T hold | let-go             the hand takes the handle / lets it move freely
//   T move X Y Z DUR            the hand moves to (X, Y, Z) over DUR s
//   T grab | release            press / release the grasp button (button 1)
//   T clutch on|off             press / release the clutch button (button 2)
//   T mode on|off               press / release the mode button (button 3: each
//                               press switches pull / spool mode)
//   T pull DX DY DZ DUR         grab, then move by (DX, DY, DZ) over DUR s
//   T drag DX DY DZ DUR [S]     spool mode: grab and drag by (DX, DY, DZ) over DUR s
//                               in strokes of at most S mm (default 60): after each
//                               stroke but the last the hand returns with the
//                               clutch held, so the drag can exceed the workspace
//   T drop F                    drop the fraction F (0..1) of frames from now on
//   T silent DUR                send and receive nothing for DUR s
//   T garbage N                 send N frames of random identifiers, lengths, bytes
//   T wrong-length DUR          send own frames with wrong lengths for DUR s
//   T freeze DUR                repeat the last position frame unchanged for DUR s
//   T reboot [DUR]              power off for DUR s (default 0.2), then boot
//   T bus-off DUR               report bus-off, go silent for DUR s, report restart
//   T emergency KIND DUR        raise a fault for DUR s; KIND: over-current,
//                               over-temperature, amplifier, encoder
//   T end                       stop the simulation
// Motions (move, pull, drag) may not overlap, and every target must lie inside
// the workspace. Errors name the file, the line and the problem.
//
// Thread-safety: values; a Player belongs to the thread stepping its device.
// parse_script() allocates (start-up); Player::advance() does not.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "drivers/hapticsim/sim_device.hpp"

namespace visvol::hapticsim {

enum class Action : std::uint8_t {
  hold,
  let_go,
  move,
  grab,
  release,
  clutch_on,
  clutch_off,
  mode_on,
  mode_off,
  drop,
  silent,
  garbage,
  wrong_length,
  freeze,
  reboot,
  bus_off,
  emergency,
  end,
};

struct ScriptEvent {
  double time_s = 0.0;
  Action action = Action::hold;
  std::array<double, 3> target_mm{};  // move: absolute hand target (relative motions resolved)
  double duration_s = 0.0;            // move and timed faults
  double fraction = 0.0;              // drop
  std::uint32_t count = 0;            // garbage
  std::uint16_t fault_bit = 0;        // emergency: haptic::kFault*
  int line = 0;                       // source line
};

struct Script {
  std::vector<ScriptEvent> events;  // by time; equal times keep file order
  double end_s = 0.0;               // when everything in it is over (or its `end`)
  bool has_end = false;
};

// Parses a script; `source` names it in errors ("scripts/pull.txt").
Result<Script> parse_script(const std::string& text, const std::string& source,
                            const std::array<double, 3>& workspace_half_mm);
Result<Script> load_script(const std::string& path, const std::array<double, 3>& workspace_half_mm);

// Plays a script onto a device: call advance() before each device step.
class Player {
 public:
  explicit Player(const Script& script) : script_(&script) {}  // script outlives the player

  // Applies every event due by t_s (seconds since the start; now_ns the
  // device's clock at that time) and sets the hand.
  void advance(double t_s, std::int64_t now_ns, SimDevice& device);
  // True once an `end` event is due.
  bool ended() const { return ended_; }

 private:
  void apply(const ScriptEvent& e, std::int64_t now_ns, SimDevice& device);

  const Script* script_;
  std::size_t next_ = 0;
  bool ended_ = false;
  Hand hand_;
  // The current motion: from -> to over [t0, t1].
  std::array<double, 3> from_mm_{};
  std::array<double, 3> to_mm_{};
  double t0_s_ = 0.0;
  double t1_s_ = 0.0;
};

}  // namespace visvol::hapticsim
