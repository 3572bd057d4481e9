// The bus interface every CAN driver in visvol talks through: send one frame,
// receive pending frames with their timestamps, never block.
//
// Implementations: SocketCanBus (a raw SocketCAN socket, socketcan_bus.hpp) on
// consoles and vcan rigs, MemoryBus (memory_bus.hpp) in unit tests. Drivers take
// a CanBus& and never know which one they have.
//
// Ownership: the caller owns the bus and keeps it alive while drivers use it.
// Thread-safety: one thread per bus object (the real-time thread); counters are
// plain integers read from that thread (publish a copy through LatestValue for
// others). Cost and real-time safety: send() and receive() never allocate, never
// log and never block; SocketCanBus makes one system call per send and one per
// batch of up to 16 received frames.
#pragma once

#include <cstddef>
#include <cstdint>

#include "base/status.hpp"
#include "drivers/can/can_frame.hpp"

namespace visvol::can {

// Counters of one bus endpoint, monotonically increasing from open.
struct CanCounters {
  std::uint64_t received = 0;        // frames handed to the caller (data and error frames)
  std::uint64_t sent = 0;            // frames the interface accepted for sending
  std::uint64_t send_failed = 0;     // frames refused: transmit queue full, interface down, bad frame
  std::uint64_t dropped = 0;         // frames lost in a full receive queue (SocketCAN: SO_RXQ_OVFL)
  std::uint64_t malformed = 0;       // reads that were not one whole classic frame (discarded)
  std::uint64_t receive_errors = 0;  // receive calls that failed other than "nothing pending"
  std::uint64_t error_frames = 0;    // error frames received, of which:
  std::uint64_t bus_errors = 0;      //   protocol, acknowledgement, timeout, transceiver errors
  std::uint64_t bus_off = 0;         //   bus-off
  std::uint64_t restarts = 0;        //   controller restarted after bus-off
};

// Passes standard (11-bit) data frames whose identifier matches `id` in the bits
// set in `mask`. Extended and remote frames never pass a filter.
struct CanFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = kStandardIdMask;
};

class CanBus {
 public:
  virtual ~CanBus() = default;

  // Queues one frame for sending without blocking: Errc::ok; Errc::resource when
  // the transmit queue is full; Errc::io when the interface is down or bus-off;
  // Errc::invalid_argument for a frame longer than 8 bytes. Counted either way.
  virtual Errc send(const CanFrame& frame) = 0;

  // Moves up to `capacity` pending frames into out[0..), oldest first, and
  // returns how many. Fewer than `capacity` means nothing more is pending now.
  virtual std::size_t receive(CanFrame* out, std::size_t capacity) = 0;

  virtual const CanCounters& counters() const = 0;
};

// Counts an error frame in `counters` (shared by every implementation).
inline void count_error_frame(CanCounters& counters, const CanFrame& frame) {
  const ErrorInfo info = classify_error(frame);
  ++counters.error_frames;
  if (info.bus_error) ++counters.bus_errors;
  if (info.bus_off) ++counters.bus_off;
  if (info.restarted) ++counters.restarts;
}

// Hands every pending frame to on_frame(const CanFrame&) through `batch` (a
// caller-owned array, N frames), stopping after `max_frames` so that a babbling
// node cannot stall a tick. Returns the number handed on; `*capped` tells whether
// it stopped at the cap. Real-time safe when on_frame is.
template <std::size_t N, typename OnFrame>
std::size_t drain(CanBus& bus, CanFrame (&batch)[N], std::size_t max_frames, bool* capped, OnFrame&& on_frame) {
  std::size_t total = 0;
  *capped = false;
  while (total < max_frames) {
    const std::size_t want = max_frames - total < N ? max_frames - total : N;
    const std::size_t got = bus.receive(batch, want);
    for (std::size_t i = 0; i < got; ++i) on_frame(batch[i]);
    total += got;
    if (got < want) return total;
  }
  *capped = true;
  return total;
}

}  // namespace visvol::can
