// The haptic device protocol as data: identifiers, scales, timing, wire layouts.
//
// Classic CAN at 1 Mbit/s, CANopen-style identifiers (function code << 7 | node),
// little-endian signals. haptic.dbc describes the same frames for bus tools and
// protocol.md the state machine; tests check all three agree.
//
//   id          dir              rate       content
//   0x000       console->device  on demand  NMT command (start, stop, pre-op, reset)
//   0x080+n     device->console  on event   emergency: fault code, register, axis, temp, current
//   0x180+n     device->console  1 kHz      position x, y, z (0.01 mm), buttons, sequence
//   0x200+n     console->device  1 kHz      force x, y, z (1 mN), enable, sequence
//   0x280+n     device->console  100 Hz     status: NMT state, flags, faults, motor temp
//   0x700+n     device->console  20 Hz      heartbeat: NMT state (0x00 once at boot)
//
// Header-only constants; nothing here allocates or does I/O.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace visvol::haptic {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "wire structs are copied as-is: the protocol is little-endian");

// Node identifiers: the CANopen range; 0 addresses every node (NMT only).
inline constexpr std::uint8_t kMinNodeId = 1;
inline constexpr std::uint8_t kMaxNodeId = 127;
inline constexpr std::uint8_t kDefaultNodeId = 1;
inline constexpr std::uint32_t kNodeMask = 0x7F;

enum class MessageKind : std::uint8_t { nmt, emergency, position, command, status, heartbeat };
inline constexpr std::size_t kMessageKinds = 6;

// Identifier bases (CANopen predefined connection set): id = base + node.
inline constexpr std::uint32_t kNmtId = 0x000;
inline constexpr std::uint32_t kEmergencyBase = 0x080;
inline constexpr std::uint32_t kPositionBase = 0x180;  // TPDO1
inline constexpr std::uint32_t kCommandBase = 0x200;   // RPDO1
inline constexpr std::uint32_t kStatusBase = 0x280;    // TPDO2
inline constexpr std::uint32_t kHeartbeatBase = 0x700;

// One frame of the protocol.
struct FrameSpec {
  MessageKind kind;
  const char* name;    // as in haptic.dbc
  std::uint32_t base;  // identifier for node 0; add the node id (except NMT)
  std::uint8_t dlc;    // data length, bytes (exactly this; anything else is malformed)
  bool from_device;    // sent by the device (else by the console)
  double rate_hz;      // nominal rate while operational; 0: on event or demand
};

inline constexpr std::array<FrameSpec, kMessageKinds> kFrames = {{
    {MessageKind::nmt, "NMT", kNmtId, 2, false, 0.0},
    {MessageKind::emergency, "Emergency", kEmergencyBase, 8, true, 0.0},
    {MessageKind::position, "Position", kPositionBase, 8, true, 1000.0},
    {MessageKind::command, "ForceCommand", kCommandBase, 8, false, 1000.0},
    {MessageKind::status, "Status", kStatusBase, 8, true, 100.0},
    {MessageKind::heartbeat, "Heartbeat", kHeartbeatBase, 1, true, 20.0},
}};

constexpr const FrameSpec& frame_spec(MessageKind kind) { return kFrames[static_cast<std::size_t>(kind)]; }
constexpr std::uint32_t frame_id(MessageKind kind, std::uint8_t node) {
  return kind == MessageKind::nmt ? kNmtId : frame_spec(kind).base + node;
}
static_assert(frame_spec(MessageKind::heartbeat).kind == MessageKind::heartbeat &&
                  frame_spec(MessageKind::status).kind == MessageKind::status &&
                  frame_spec(MessageKind::command).kind == MessageKind::command &&
                  frame_spec(MessageKind::position).kind == MessageKind::position &&
                  frame_spec(MessageKind::emergency).kind == MessageKind::emergency &&
                  frame_spec(MessageKind::nmt).kind == MessageKind::nmt,
              "kFrames is indexed by MessageKind");
static_assert(frame_id(MessageKind::position, kMaxNodeId) < frame_id(MessageKind::command, kMinNodeId) &&
                  frame_id(MessageKind::command, kMaxNodeId) < frame_id(MessageKind::status, kMinNodeId) &&
                  frame_id(MessageKind::heartbeat, kMaxNodeId) <= 0x7FF,
              "identifier ranges of different kinds never overlap");

// Scales: physical value = counts x scale.
inline constexpr double kPositionMmPerCount = 0.01;      // encoder resolution
inline constexpr double kForceNPerCount = 0.001;         // 1 mN
inline constexpr double kTemperatureDegCPerCount = 0.1;  // 0.1 degC
inline constexpr double kCurrentAPerCount = 0.001;       // 1 mA

// Timing (ns).
inline constexpr std::int64_t kPositionPeriodNs = 1'000'000;
inline constexpr std::int64_t kCommandPeriodNs = 1'000'000;
inline constexpr std::int64_t kStatusPeriodNs = 10'000'000;
inline constexpr std::int64_t kHeartbeatPeriodNs = 50'000'000;
// The device applies no force when no command arrived for this long.
inline constexpr std::int64_t kDeviceCommandTimeoutNs = 10'000'000;
// The console commands zero force when no position arrived for this long.
inline constexpr std::int64_t kConsolePositionTimeoutNs = 10'000'000;
// The console declares the device lost when neither heartbeat nor status arrived
// for this long (four heartbeat periods).
inline constexpr std::int64_t kHeartbeatTimeoutNs = 200'000'000;
// The console repeats NMT start this often until the device is operational.
inline constexpr std::int64_t kNmtRetryNs = 100'000'000;
// A latched emergency clears after clean status frames for this long (when the
// emergency reset frame itself was lost).
inline constexpr std::int64_t kFaultClearNs = 50'000'000;

// NMT states as heartbeat and status report them (CANopen values).
enum class NmtState : std::uint8_t {
  boot_up = 0x00,
  stopped = 0x04,
  operational = 0x05,
  pre_operational = 0x7F,
};
constexpr bool valid_nmt_state(std::uint8_t v) { return v == 0x00 || v == 0x04 || v == 0x05 || v == 0x7F; }

// NMT commands (CANopen values).
enum class NmtCommand : std::uint8_t {
  start = 0x01,
  stop = 0x02,
  enter_pre_operational = 0x80,
  reset_node = 0x81,
  reset_communication = 0x82,
};
constexpr bool valid_nmt_command(std::uint8_t v) {
  return v == 0x01 || v == 0x02 || v == 0x80 || v == 0x81 || v == 0x82;
}

// Position frame, buttons byte.
inline constexpr std::uint8_t kButtonGrasp = 0x01;   // stylus button 1: grasp the rope
inline constexpr std::uint8_t kButtonClutch = 0x02;  // stylus button 2: clutch (re-index)
inline constexpr std::uint8_t kButtonMode = 0x04;    // button 3 (a foot switch or panel key): pull / spool mode
inline constexpr std::uint8_t kButtonsReserved = 0xF8;

// Force command, flags byte.
inline constexpr std::uint8_t kCommandEnable = 0x01;  // apply the force (else zero)
inline constexpr std::uint8_t kCommandReserved = 0xFE;

// Status, flags byte.
inline constexpr std::uint8_t kStatusForceEnabled = 0x01;  // amplifiers on, command applied
inline constexpr std::uint8_t kStatusWatchdog = 0x02;      // no command for 10 ms: force zeroed
inline constexpr std::uint8_t kStatusSaturated = 0x04;     // last command clipped to the peak force
inline constexpr std::uint8_t kStatusReserved = 0xF8;

// Status fault bits (any bit set, known or not, is a fault).
inline constexpr std::uint16_t kFaultOverCurrent = 0x0001;
inline constexpr std::uint16_t kFaultOverTemperature = 0x0002;
inline constexpr std::uint16_t kFaultAmplifier = 0x0004;
inline constexpr std::uint16_t kFaultEncoder = 0x0008;

// Emergency codes (CiA 301 classes) and the fault bit each one raises.
struct EmergencySpec {
  std::uint16_t code;
  std::uint16_t fault_bit;
  std::uint8_t error_register;  // CANopen error register (bit 0: generic error)
  const char* name;
};
inline constexpr std::array<EmergencySpec, 5> kEmergencies = {{
    {0x0000, 0, 0x00, "error reset"},
    {0x2310, kFaultOverCurrent, 0x03, "over-current"},          // generic | current
    {0x4210, kFaultOverTemperature, 0x09, "over-temperature"},  // generic | temperature
    {0x5000, kFaultAmplifier, 0x81, "amplifier"},               // generic | manufacturer
    {0x7305, kFaultEncoder, 0x81, "encoder"},                   // generic | manufacturer
}};
// The name of an emergency code ("unknown" for codes not in the table).
constexpr const char* emergency_name(std::uint16_t code) {
  for (const EmergencySpec& e : kEmergencies) {
    if (e.code == code) return e.name;
  }
  return "unknown";
}
inline constexpr std::uint8_t kAxisNone = 0xFF;

// Wire layouts: copied byte for byte into and out of CanFrame::data.
namespace wire {

struct Position {
  std::int16_t x_counts;  // 0.01 mm, device frame
  std::int16_t y_counts;
  std::int16_t z_counts;
  std::uint8_t buttons;   // kButton*
  std::uint8_t sequence;  // +1 per frame, wraps
};
struct Command {
  std::int16_t fx_counts;  // 1 mN, device frame
  std::int16_t fy_counts;
  std::int16_t fz_counts;
  std::uint8_t flags;     // kCommand*
  std::uint8_t sequence;  // +1 per frame, wraps
};
struct Status {
  std::uint8_t nmt_state;           // NmtState
  std::uint8_t flags;               // kStatus*
  std::uint16_t fault_bits;         // kFault*
  std::int16_t temperature_counts;  // hottest motor, 0.1 degC
  std::uint8_t reserved;            // zero
  std::uint8_t sequence;            // +1 per frame, wraps
};
struct Emergency {
  std::uint16_t code;               // kEmergencies; 0x0000: every fault cleared
  std::uint8_t error_register;      // 0: no error remains
  std::uint8_t axis;                // motor 0..2, or kAxisNone
  std::int16_t temperature_counts;  // that motor's temperature, 0.1 degC
  std::uint16_t current_counts;     // that motor's current, 1 mA
};
struct Heartbeat {
  std::uint8_t state;  // NmtState
};
struct Nmt {
  std::uint8_t command;  // NmtCommand
  std::uint8_t node;     // 0: every node
};

template <typename T>
constexpr bool kPlain = std::is_trivially_copyable_v<T>&& std::is_standard_layout_v<T>;

static_assert(kPlain<Position> && sizeof(Position) == 8 && offsetof(Position, y_counts) == 2 &&
              offsetof(Position, z_counts) == 4 && offsetof(Position, buttons) == 6 &&
              offsetof(Position, sequence) == 7);
static_assert(kPlain<Command> && sizeof(Command) == 8 && offsetof(Command, fy_counts) == 2 &&
              offsetof(Command, fz_counts) == 4 && offsetof(Command, flags) == 6 && offsetof(Command, sequence) == 7);
static_assert(kPlain<Status> && sizeof(Status) == 8 && offsetof(Status, flags) == 1 &&
              offsetof(Status, fault_bits) == 2 && offsetof(Status, temperature_counts) == 4 &&
              offsetof(Status, reserved) == 6 && offsetof(Status, sequence) == 7);
static_assert(kPlain<Emergency> && sizeof(Emergency) == 8 && offsetof(Emergency, error_register) == 2 &&
              offsetof(Emergency, axis) == 3 && offsetof(Emergency, temperature_counts) == 4 &&
              offsetof(Emergency, current_counts) == 6);
static_assert(kPlain<Heartbeat> && sizeof(Heartbeat) == 1);
static_assert(kPlain<Nmt> && sizeof(Nmt) == 2 && offsetof(Nmt, node) == 1);

}  // namespace wire

static_assert(sizeof(wire::Nmt) == frame_spec(MessageKind::nmt).dlc &&
                  sizeof(wire::Emergency) == frame_spec(MessageKind::emergency).dlc &&
                  sizeof(wire::Position) == frame_spec(MessageKind::position).dlc &&
                  sizeof(wire::Command) == frame_spec(MessageKind::command).dlc &&
                  sizeof(wire::Status) == frame_spec(MessageKind::status).dlc &&
                  sizeof(wire::Heartbeat) == frame_spec(MessageKind::heartbeat).dlc,
              "every layout fills its frame exactly");

// Signals as haptic.dbc declares them (Intel byte order; start bit = the
// signal's least significant bit). Reserved fields are signals too (named
// *Reserved, always 0) so that bus tools show a violation; the signals of a
// frame cover each of its bits exactly once.
struct SignalSpec {
  MessageKind kind;
  const char* name;
  std::uint8_t start_bit;
  std::uint8_t length_bits;
  bool is_signed;
  double scale;
  const char* unit;
};
inline constexpr std::array<SignalSpec, 35> kSignals = {{
    {MessageKind::nmt, "NMT_Command", 0, 8, false, 1.0, ""},
    {MessageKind::nmt, "NMT_Node", 8, 8, false, 1.0, ""},
    {MessageKind::emergency, "Emcy_Code", 0, 16, false, 1.0, ""},
    {MessageKind::emergency, "Emcy_Register", 16, 8, false, 1.0, ""},
    {MessageKind::emergency, "Emcy_Axis", 24, 8, false, 1.0, ""},
    {MessageKind::emergency, "Emcy_Temperature", 32, 16, true, kTemperatureDegCPerCount, "degC"},
    {MessageKind::emergency, "Emcy_Current", 48, 16, false, kCurrentAPerCount, "A"},
    {MessageKind::position, "Pos_X", 0, 16, true, kPositionMmPerCount, "mm"},
    {MessageKind::position, "Pos_Y", 16, 16, true, kPositionMmPerCount, "mm"},
    {MessageKind::position, "Pos_Z", 32, 16, true, kPositionMmPerCount, "mm"},
    {MessageKind::position, "Pos_ButtonGrasp", 48, 1, false, 1.0, ""},
    {MessageKind::position, "Pos_ButtonClutch", 49, 1, false, 1.0, ""},
    {MessageKind::position, "Pos_ButtonMode", 50, 1, false, 1.0, ""},
    {MessageKind::position, "Pos_ButtonsReserved", 51, 5, false, 1.0, ""},
    {MessageKind::position, "Pos_Sequence", 56, 8, false, 1.0, ""},
    {MessageKind::command, "Cmd_ForceX", 0, 16, true, kForceNPerCount, "N"},
    {MessageKind::command, "Cmd_ForceY", 16, 16, true, kForceNPerCount, "N"},
    {MessageKind::command, "Cmd_ForceZ", 32, 16, true, kForceNPerCount, "N"},
    {MessageKind::command, "Cmd_Enable", 48, 1, false, 1.0, ""},
    {MessageKind::command, "Cmd_FlagsReserved", 49, 7, false, 1.0, ""},
    {MessageKind::command, "Cmd_Sequence", 56, 8, false, 1.0, ""},
    {MessageKind::status, "St_NmtState", 0, 8, false, 1.0, ""},
    {MessageKind::status, "St_ForceEnabled", 8, 1, false, 1.0, ""},
    {MessageKind::status, "St_Watchdog", 9, 1, false, 1.0, ""},
    {MessageKind::status, "St_Saturated", 10, 1, false, 1.0, ""},
    {MessageKind::status, "St_FlagsReserved", 11, 5, false, 1.0, ""},
    {MessageKind::status, "St_FaultOverCurrent", 16, 1, false, 1.0, ""},
    {MessageKind::status, "St_FaultOverTemperature", 17, 1, false, 1.0, ""},
    {MessageKind::status, "St_FaultAmplifier", 18, 1, false, 1.0, ""},
    {MessageKind::status, "St_FaultEncoder", 19, 1, false, 1.0, ""},
    {MessageKind::status, "St_FaultOther", 20, 12, false, 1.0, ""},
    {MessageKind::status, "St_MotorTemperature", 32, 16, true, kTemperatureDegCPerCount, "degC"},
    {MessageKind::status, "St_Reserved", 48, 8, false, 1.0, ""},
    {MessageKind::status, "St_Sequence", 56, 8, false, 1.0, ""},
    {MessageKind::heartbeat, "Hb_State", 0, 8, false, 1.0, ""},
}};

// The signals of each frame cover each of its bits exactly once.
constexpr bool signals_tile_frames() {
  for (const FrameSpec& f : kFrames) {
    std::uint64_t covered = 0;
    for (const SignalSpec& s : kSignals) {
      if (s.kind != f.kind) continue;
      if (s.length_bits == 0 || s.start_bit + s.length_bits > 8 * f.dlc) return false;
      const std::uint64_t bits = (s.length_bits == 64 ? ~0ull : ((1ull << s.length_bits) - 1)) << s.start_bit;
      if ((covered & bits) != 0) return false;
      covered |= bits;
    }
    if (covered != (f.dlc == 8 ? ~0ull : ((1ull << (8 * f.dlc)) - 1))) return false;
  }
  return true;
}
static_assert(signals_tile_frames(), "kSignals must tile every frame without overlap");

// Classic CAN frame length on the wire, bits: 47 framing bits (SOF, 11-bit id,
// RTR, IDE, r0, DLC, 15-bit CRC, delimiters, ACK, EOF, IFS) plus the data.
constexpr unsigned frame_bits(std::uint8_t dlc) { return 47u + 8u * dlc; }
// Worst case with bit stuffing: one stuff bit per 4 bits after the first 5 of
// the 34 + 8 dlc bits from SOF to the end of the CRC.
constexpr unsigned frame_bits_stuffed(std::uint8_t dlc) { return frame_bits(dlc) + (34u + 8u * dlc - 1u) / 4u; }
static_assert(frame_bits(8) == 111 && frame_bits_stuffed(8) == 135);
static_assert(frame_bits(0) == 47 && frame_bits_stuffed(0) == 55);

}  // namespace visvol::haptic
