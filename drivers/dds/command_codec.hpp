// Commands between DDS and the plain Command of msg/samples.hpp: decoding,
// validation against what the console reserved and loaded, and encoding for
// senders. Pure: no DDS entities, no I/O, no globals; libFuzzer drives it
// (tests/drivers/dds/command_fuzz.cpp).
//
// Every rejection is a Status (invalid_argument) whose message names the
// field as the sender wrote it (the IDL name, e.g. "start_m.x" or
// "constraints[2].kind") and the problem, and goes back to the sender in the
// acknowledgement.
//
// Thread-safety: functions are reentrant; objects are used by one thread at a
// time. Cost: O(constraints); a rejection allocates its message. Not for the
// real-time thread.
#pragma once

#include <cstdint>
#include <string_view>

#include "base/status.hpp"
#include "msg/samples.hpp"
#include "visvol_msgs.h"

namespace visvol::dds {

// the console's own pack, its --terrain packs and its catalogue's verified ones
inline constexpr std::size_t kMaxKnownPacks = 64;

// What commands are validated against. The console fills it from its loaded
// pack (bounds), its reservations (segments, constraints) and its
// configuration (ranges, the packs on the console), and replaces it after a
// terrain switch.
struct CommandLimits {
  msg::WorldPoint min{};  // pack bounds, world metres, inclusive: endpoints and
  msg::WorldPoint max{};  // observers must lie inside
  // The pack's planning bounds (x and y, inclusive), where F_p counts every
  // observer: endpoints must lie inside them too. Both zero: unset.
  msg::WorldPoint plan_min{};
  msg::WorldPoint plan_max{};
  std::uint32_t min_segments = 2;
  std::uint32_t max_segments = msg::kMaxPathVertices - 1;  // rope segments reserved
  std::uint32_t max_constraints = msg::kMaxConstraints;    // constraints reserved
  // hidden-from and visible-to points together: what the console takes (--max-observers)
  std::uint32_t max_observers = 2 * msg::kMaxObserversPerKind;
  double max_weight = 1e6;                      // each of k1..k4 in [0, max]
  double max_stretch_stiffness_n_per_m = 1e6;   // in (0, max]
  double max_bend_stiffness_n_m_per_rad = 1e6;  // in [0, max]
  double max_clearance_m = 10000.0;             // clearance in [0, max], max-agl in (0, max];
                                                // max-altitude within the pack's z range
  std::uint32_t pack_count = 0;                 // packs a terrain switch may name
  char packs[kMaxKnownPacks][msg::kPackIdCapacity] = {};
};

// Checks the limits themselves (console configuration): finite, ordered
// bounds, capacities within msg/samples.hpp, known pack ids well-formed.
Status validate_limits(const CommandLimits& limits);
// Adds a pack a terrain switch may name (checked like a command's pack_id).
Status add_known_pack(CommandLimits& limits, std::string_view pack_id);

// Well-formed names: source 1..63 printable ASCII characters; pack id
// 1..63 of [A-Za-z0-9._-].
Status check_source(std::string_view source);
Status check_pack_id(std::string_view field, std::string_view pack_id);

// Structure: a known kind, well-formed text, counts that fit, known enum
// values. Fills `out` (zeroed first: fields of other kinds stay zero).
Status decode_command(const visvol_msgs_msg_dds__Command_& msg, msg::Command& out);
// Values: finite numbers, positions inside the pack, counts within what was
// reserved, ranges of the limits, a pack the console has. set-constraints:
// at most one each of clearance, max-agl and max-altitude, a max-agl above
// the clearance given with it, at most kMaxObserversPerKind observers of a
// kind and max_observers in all.
Status validate_command(const msg::Command& command, const CommandLimits& limits);
// Both, as command intake applies them.
Status decode_and_validate(const visvol_msgs_msg_dds__Command_& msg, const CommandLimits& limits, msg::Command& out);

// Sender side: a Command as the DDS message, in buffers this object owns.
class CommandMessage {
 public:
  CommandMessage() = default;
  CommandMessage(const CommandMessage&) = delete;
  CommandMessage& operator=(const CommandMessage&) = delete;
  // Valid until the next fill().
  const visvol_msgs_msg_dds__Command_& fill(const msg::Command& command);

 private:
  char source_[msg::kSourceCapacity] = {};
  char pack_id_[msg::kPackIdCapacity] = {};
  visvol_msgs_msg_dds__Constraint_ constraints_[msg::kMaxConstraints] = {};
  visvol_msgs_msg_dds__Command_ msg_{};
};

// An acknowledgement as the DDS message, in buffers this object owns.
class AckMessage {
 public:
  explicit AckMessage(std::string frame_id);
  AckMessage(const AckMessage&) = delete;
  AckMessage& operator=(const AckMessage&) = delete;
  // Valid until the next fill(). Stamps it now.
  const visvol_msgs_msg_dds__CommandAck_& fill(const msg::CommandAck& ack);

 private:
  std::string frame_id_;
  char source_[msg::kSourceCapacity] = {};
  char reason_[msg::kReasonCapacity] = {};
  visvol_msgs_msg_dds__CommandAck_ msg_{};
};

// A received acknowledgement back into the plain struct (texts truncated to
// fit; result kept as received even when unknown).
msg::CommandAck decode_ack(const visvol_msgs_msg_dds__CommandAck_& msg);

}  // namespace visvol::dds
