// One classic CAN frame as the rest of visvol sees it, and the error classes a
// controller reports in error frames.
//
// Plain data, no I/O. The error-class bits and controller-status bits mirror
// linux/can/error.h (socketcan_bus.cpp static_asserts that they match) so that
// nothing outside the SocketCAN file needs the Linux headers.
//
// Thread-safety: values. Cost: every function here is O(1), allocation-free and
// real-time safe.
#pragma once

#include <array>
#include <cstdint>

namespace visvol::can {

inline constexpr std::uint8_t kMaxDataBytes = 8;               // classic CAN
inline constexpr std::uint32_t kStandardIdMask = 0x7FFu;       // 11-bit identifier
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFFu;  // 29-bit identifier

struct CanFrame {
  // Frame kinds (bits of `flags`).
  static constexpr std::uint8_t kExtended = 0x01;  // 29-bit identifier
  static constexpr std::uint8_t kRemote = 0x02;    // remote transmission request
  static constexpr std::uint8_t kError = 0x04;     // error frame: `id` holds error classes

  std::int64_t timestamp_ns = 0;  // receive time, CLOCK_MONOTONIC ns; ignored on send
  std::uint32_t id = 0;           // identifier without flag bits (or error classes)
  std::uint8_t len = 0;           // data length, bytes, 0..8
  std::uint8_t flags = 0;         // kExtended | kRemote | kError
  std::array<std::uint8_t, kMaxDataBytes> data{};

  constexpr bool is_error() const { return (flags & kError) != 0; }
  // A standard 11-bit data frame: the only kind the haptic protocol uses.
  constexpr bool is_standard_data() const { return flags == 0 && id <= kStandardIdMask; }
};

// Error classes carried in CanFrame::id of an error frame (linux/can/error.h).
namespace err {
inline constexpr std::uint32_t kTxTimeout = 0x001;
inline constexpr std::uint32_t kLostArbitration = 0x002;
inline constexpr std::uint32_t kController = 0x004;  // details in data[1]
inline constexpr std::uint32_t kProtocol = 0x008;    // details in data[2..3]
inline constexpr std::uint32_t kTransceiver = 0x010;
inline constexpr std::uint32_t kNoAck = 0x020;
inline constexpr std::uint32_t kBusOff = 0x040;
inline constexpr std::uint32_t kBusError = 0x080;
inline constexpr std::uint32_t kRestarted = 0x100;
inline constexpr std::uint32_t kCounters = 0x200;  // error counters in data[6..7]
inline constexpr std::uint32_t kAllClasses = 0x1FFFFFFFu;

// Controller status bits in data[1] of a kController error frame.
inline constexpr std::uint8_t kCtrlRxOverflow = 0x01;
inline constexpr std::uint8_t kCtrlTxOverflow = 0x02;
inline constexpr std::uint8_t kCtrlRxWarning = 0x04;
inline constexpr std::uint8_t kCtrlTxWarning = 0x08;
inline constexpr std::uint8_t kCtrlRxPassive = 0x10;
inline constexpr std::uint8_t kCtrlTxPassive = 0x20;
inline constexpr std::uint8_t kCtrlActive = 0x40;  // back to error-active
}  // namespace err

// What an error frame means for a driver.
struct ErrorInfo {
  bool bus_off = false;      // the controller left the bus: nothing is sent or received
  bool restarted = false;    // the controller is back on the bus after bus-off
  bool bus_error = false;    // a protocol, acknowledgement, timeout or transceiver error
  bool passive = false;      // error-passive (warning before bus-off)
  bool rx_overflow = false;  // the controller lost received frames
};

// Classifies an error frame; all false for anything else.
constexpr ErrorInfo classify_error(const CanFrame& frame) {
  ErrorInfo info;
  if (!frame.is_error()) return info;
  const std::uint32_t cls = frame.id;
  const std::uint8_t ctrl = (cls & err::kController) != 0 && frame.len > 1 ? frame.data[1] : 0;
  info.bus_off = (cls & err::kBusOff) != 0;
  info.restarted = (cls & err::kRestarted) != 0;
  info.bus_error = (cls & (err::kBusError | err::kProtocol | err::kNoAck | err::kTxTimeout | err::kTransceiver)) != 0;
  info.passive = (ctrl & (err::kCtrlRxPassive | err::kCtrlTxPassive)) != 0;
  info.rx_overflow = (ctrl & err::kCtrlRxOverflow) != 0;
  return info;
}

}  // namespace visvol::can
