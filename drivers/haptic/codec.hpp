// The haptic protocol codec: (timestamp, id, bytes) -> message, and back.
//
// Pure functions over plain data: no sockets, no clocks, no allocation, no
// logging. Decoding validates everything a frame from outside can get wrong
// (identifier, length, reserved bits, enumerated values) and returns a
// DecodeError instead of a message; the caller counts it. Encoding is total:
// values beyond a signal's range saturate and NaN encodes as 0 (callers check
// finiteness first where it matters); force commands round toward zero, so an
// encoded force is never larger than the one asked for.
//
// Thread-safety: none needed (no state). Cost: O(1), a few dozen instructions.
// Real-time safe.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "drivers/can/can_frame.hpp"
#include "drivers/haptic/protocol.hpp"

namespace visvol::haptic {

struct PositionMsg {
  std::array<double, 3> pos_mm{};  // handle position, device frame, mm
  std::uint8_t buttons = 0;        // kButtonGrasp | kButtonClutch
  std::uint8_t sequence = 0;
};
struct CommandMsg {
  std::array<double, 3> force_n{};  // force on the handle, device frame, N
  bool enable = false;              // false: the device applies zero force
  std::uint8_t sequence = 0;
};
struct StatusMsg {
  NmtState nmt_state = NmtState::boot_up;
  std::uint8_t flags = 0;        // kStatus*
  std::uint16_t fault_bits = 0;  // kFault*; any bit set is a fault
  double motor_temperature_c = 0.0;
  std::uint8_t sequence = 0;
};
struct EmergencyMsg {
  std::uint16_t code = 0;           // kEmergencies; 0: every fault cleared
  std::uint8_t error_register = 0;  // 0: no error remains
  std::uint8_t axis = kAxisNone;    // motor 0..2 or kAxisNone
  double temperature_c = 0.0;       // that motor's temperature
  double current_a = 0.0;           // that motor's current
};
struct HeartbeatMsg {
  NmtState state = NmtState::boot_up;
};
struct NmtMsg {
  NmtCommand command = NmtCommand::start;
  std::uint8_t node = 0;  // addressed node; 0: every node
};

// One decoded frame: `kind` says which member holds it.
struct Message {
  MessageKind kind = MessageKind::heartbeat;
  std::int64_t timestamp_ns = 0;  // receive time, as given to decode()
  std::uint8_t node = 0;          // node named by the identifier (0 for NMT)
  PositionMsg position;
  CommandMsg command;
  StatusMsg status;
  EmergencyMsg emergency;
  HeartbeatMsg heartbeat;
  NmtMsg nmt;
};

enum class DecodeError : std::uint8_t {
  ok,
  not_data_frame,  // error, remote or extended frame
  unknown_id,      // not an identifier of this protocol
  wrong_length,    // data length differs from the frame's fixed length
  reserved_bits,   // a reserved bit or byte is not zero
  bad_value,       // an enumerated field holds an unknown value
};
inline constexpr std::size_t kDecodeErrors = 6;
const char* decode_error_name(DecodeError error);

// Decodes one frame into `out`. On any error `out` is unspecified.
DecodeError decode(std::int64_t timestamp_ns, std::uint32_t id, const std::uint8_t* data, std::size_t len,
                   Message& out);
DecodeError decode(const can::CanFrame& frame, Message& out);

can::CanFrame encode(const PositionMsg& msg, std::uint8_t node);
can::CanFrame encode(const CommandMsg& msg, std::uint8_t node);
can::CanFrame encode(const StatusMsg& msg, std::uint8_t node);
can::CanFrame encode(const EmergencyMsg& msg, std::uint8_t node);
can::CanFrame encode(const HeartbeatMsg& msg, std::uint8_t node);
can::CanFrame encode(const NmtMsg& msg);
// Encodes the member `msg.kind` names, for `msg.node`.
can::CanFrame encode(const Message& msg);

// Euclidean length of a 3-vector of a message (a force in N, a step in mm).
inline double norm3(const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// Signal conversions (exposed for tests and the simulator): physical value ->
// counts, rounded to nearest, saturated to the signal's range, NaN -> 0.
std::int16_t to_counts_i16(double value, double unit_per_count);
std::uint16_t to_counts_u16(double value, double unit_per_count);
// As to_counts_i16 but toward zero, so that encoding never makes a force larger
// (values within 1e-6 count of an integer count, as decoded values are, keep it).
std::int16_t to_counts_i16_toward_zero(double value, double unit_per_count);

}  // namespace visvol::haptic
