#include "drivers/haptic/codec.hpp"

#include <cmath>
#include <cstring>

namespace visvol::haptic {
namespace {

template <typename Wire>
Wire load(const std::uint8_t* data) {
  Wire w;
  std::memcpy(&w, data, sizeof(Wire));
  return w;
}

template <typename Wire>
can::CanFrame store(const Wire& w, std::uint32_t id) {
  can::CanFrame frame;
  frame.id = id;
  frame.len = sizeof(Wire);
  std::memcpy(frame.data.data(), &w, sizeof(Wire));
  return frame;
}

std::array<double, 3> to_units(std::int16_t x, std::int16_t y, std::int16_t z, double scale) {
  return {x * scale, y * scale, z * scale};
}

DecodeError decode_position(const std::uint8_t* data, PositionMsg& out) {
  const auto w = load<wire::Position>(data);
  if ((w.buttons & kButtonsReserved) != 0) return DecodeError::reserved_bits;
  out.pos_mm = to_units(w.x_counts, w.y_counts, w.z_counts, kPositionMmPerCount);
  out.buttons = w.buttons;
  out.sequence = w.sequence;
  return DecodeError::ok;
}

DecodeError decode_command(const std::uint8_t* data, CommandMsg& out) {
  const auto w = load<wire::Command>(data);
  if ((w.flags & kCommandReserved) != 0) return DecodeError::reserved_bits;
  out.force_n = to_units(w.fx_counts, w.fy_counts, w.fz_counts, kForceNPerCount);
  out.enable = (w.flags & kCommandEnable) != 0;
  out.sequence = w.sequence;
  return DecodeError::ok;
}

DecodeError decode_status(const std::uint8_t* data, StatusMsg& out) {
  const auto w = load<wire::Status>(data);
  if ((w.flags & kStatusReserved) != 0 || w.reserved != 0) return DecodeError::reserved_bits;
  if (!valid_nmt_state(w.nmt_state)) return DecodeError::bad_value;
  out.nmt_state = static_cast<NmtState>(w.nmt_state);
  out.flags = w.flags;
  out.fault_bits = w.fault_bits;
  out.motor_temperature_c = w.temperature_counts * kTemperatureDegCPerCount;
  out.sequence = w.sequence;
  return DecodeError::ok;
}

DecodeError decode_emergency(const std::uint8_t* data, EmergencyMsg& out) {
  const auto w = load<wire::Emergency>(data);
  if (w.axis > 2 && w.axis != kAxisNone) return DecodeError::bad_value;
  out.code = w.code;
  out.error_register = w.error_register;
  out.axis = w.axis;
  out.temperature_c = w.temperature_counts * kTemperatureDegCPerCount;
  out.current_a = w.current_counts * kCurrentAPerCount;
  return DecodeError::ok;
}

DecodeError decode_heartbeat(const std::uint8_t* data, HeartbeatMsg& out) {
  const auto w = load<wire::Heartbeat>(data);
  if (!valid_nmt_state(w.state)) return DecodeError::bad_value;
  out.state = static_cast<NmtState>(w.state);
  return DecodeError::ok;
}

DecodeError decode_nmt(const std::uint8_t* data, NmtMsg& out) {
  const auto w = load<wire::Nmt>(data);
  if (!valid_nmt_command(w.command) || w.node > kMaxNodeId) return DecodeError::bad_value;
  out.command = static_cast<NmtCommand>(w.command);
  out.node = w.node;
  return DecodeError::ok;
}

// The message kind an identifier names, from its CANopen function code.
bool kind_of(std::uint32_t id, MessageKind& kind, std::uint8_t& node) {
  if (id == kNmtId) {
    kind = MessageKind::nmt;
    node = 0;
    return true;
  }
  node = static_cast<std::uint8_t>(id & kNodeMask);
  if (node < kMinNodeId) return false;  // 0x080 is SYNC, others unused
  for (const FrameSpec& f : kFrames) {
    if (f.kind != MessageKind::nmt && id - node == f.base) {
      kind = f.kind;
      return true;
    }
  }
  return false;
}

}  // namespace

const char* decode_error_name(DecodeError error) {
  switch (error) {
    case DecodeError::ok: return "ok";
    case DecodeError::not_data_frame: return "not a standard data frame";
    case DecodeError::unknown_id: return "unknown identifier";
    case DecodeError::wrong_length: return "wrong data length";
    case DecodeError::reserved_bits: return "reserved bits set";
    case DecodeError::bad_value: return "unknown enumerated value";
  }
  return "invalid DecodeError";
}

DecodeError decode(std::int64_t timestamp_ns, std::uint32_t id, const std::uint8_t* data, std::size_t len,
                   Message& out) {
  if (id > can::kStandardIdMask) return DecodeError::unknown_id;
  MessageKind kind;
  std::uint8_t node;
  if (!kind_of(id, kind, node)) return DecodeError::unknown_id;
  if (len != frame_spec(kind).dlc || (len > 0 && data == nullptr)) return DecodeError::wrong_length;
  out.kind = kind;
  out.timestamp_ns = timestamp_ns;
  out.node = node;
  switch (kind) {
    case MessageKind::nmt: return decode_nmt(data, out.nmt);
    case MessageKind::emergency: return decode_emergency(data, out.emergency);
    case MessageKind::position: return decode_position(data, out.position);
    case MessageKind::command: return decode_command(data, out.command);
    case MessageKind::status: return decode_status(data, out.status);
    case MessageKind::heartbeat: return decode_heartbeat(data, out.heartbeat);
  }
  return DecodeError::unknown_id;
}

DecodeError decode(const can::CanFrame& frame, Message& out) {
  if (!frame.is_standard_data()) return DecodeError::not_data_frame;
  if (frame.len > can::kMaxDataBytes) return DecodeError::wrong_length;
  return decode(frame.timestamp_ns, frame.id, frame.data.data(), frame.len, out);
}

std::int16_t to_counts_i16(double value, double unit_per_count) {
  const double c = value / unit_per_count;
  if (std::isnan(c)) return 0;
  if (c >= 32767.0) return 32767;
  if (c <= -32768.0) return -32768;
  return static_cast<std::int16_t>(std::lround(c));
}

std::int16_t to_counts_i16_toward_zero(double value, double unit_per_count) {
  const double c = value / unit_per_count;
  if (std::isnan(c)) return 0;
  if (c >= 32767.0) return 32767;
  if (c <= -32768.0) return -32768;
  constexpr double kTolerance = 1e-6;
  return static_cast<std::int16_t>(std::trunc(c + (c > 0.0 ? kTolerance : -kTolerance)));
}

std::uint16_t to_counts_u16(double value, double unit_per_count) {
  const double c = value / unit_per_count;
  if (std::isnan(c) || c <= 0.0) return 0;
  if (c >= 65535.0) return 65535;
  return static_cast<std::uint16_t>(std::lround(c));
}

can::CanFrame encode(const PositionMsg& msg, std::uint8_t node) {
  wire::Position w{};
  w.x_counts = to_counts_i16(msg.pos_mm[0], kPositionMmPerCount);
  w.y_counts = to_counts_i16(msg.pos_mm[1], kPositionMmPerCount);
  w.z_counts = to_counts_i16(msg.pos_mm[2], kPositionMmPerCount);
  w.buttons = msg.buttons & static_cast<std::uint8_t>(~kButtonsReserved);
  w.sequence = msg.sequence;
  return store(w, frame_id(MessageKind::position, node));
}

can::CanFrame encode(const CommandMsg& msg, std::uint8_t node) {
  wire::Command w{};
  w.fx_counts = to_counts_i16_toward_zero(msg.force_n[0], kForceNPerCount);
  w.fy_counts = to_counts_i16_toward_zero(msg.force_n[1], kForceNPerCount);
  w.fz_counts = to_counts_i16_toward_zero(msg.force_n[2], kForceNPerCount);
  w.flags = msg.enable ? kCommandEnable : 0;
  w.sequence = msg.sequence;
  return store(w, frame_id(MessageKind::command, node));
}

can::CanFrame encode(const StatusMsg& msg, std::uint8_t node) {
  wire::Status w{};
  w.nmt_state = static_cast<std::uint8_t>(msg.nmt_state);
  w.flags = msg.flags & static_cast<std::uint8_t>(~kStatusReserved);
  w.fault_bits = msg.fault_bits;
  w.temperature_counts = to_counts_i16(msg.motor_temperature_c, kTemperatureDegCPerCount);
  w.sequence = msg.sequence;
  return store(w, frame_id(MessageKind::status, node));
}

can::CanFrame encode(const EmergencyMsg& msg, std::uint8_t node) {
  wire::Emergency w{};
  w.code = msg.code;
  w.error_register = msg.error_register;
  w.axis = msg.axis;
  w.temperature_counts = to_counts_i16(msg.temperature_c, kTemperatureDegCPerCount);
  w.current_counts = to_counts_u16(msg.current_a, kCurrentAPerCount);
  return store(w, frame_id(MessageKind::emergency, node));
}

can::CanFrame encode(const HeartbeatMsg& msg, std::uint8_t node) {
  const wire::Heartbeat w{static_cast<std::uint8_t>(msg.state)};
  return store(w, frame_id(MessageKind::heartbeat, node));
}

can::CanFrame encode(const NmtMsg& msg) {
  const wire::Nmt w{static_cast<std::uint8_t>(msg.command), msg.node};
  return store(w, kNmtId);
}

can::CanFrame encode(const Message& msg) {
  switch (msg.kind) {
    case MessageKind::nmt: return encode(msg.nmt);
    case MessageKind::emergency: return encode(msg.emergency, msg.node);
    case MessageKind::position: return encode(msg.position, msg.node);
    case MessageKind::command: return encode(msg.command, msg.node);
    case MessageKind::status: return encode(msg.status, msg.node);
    case MessageKind::heartbeat: return encode(msg.heartbeat, msg.node);
  }
  return can::CanFrame{};
}

}  // namespace visvol::haptic
