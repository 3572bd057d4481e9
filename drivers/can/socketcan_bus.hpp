// SocketCanBus: a CanBus on a Linux SocketCAN interface (can0, vcan0, ...).
//
// A raw CAN socket bound to the interface named in the configuration, with the
// configured receive filters, error frames enabled, non-blocking, kernel receive
// timestamps (converted to CLOCK_MONOTONIC) and the SO_RXQ_OVFL drop count. It is
// the only code in visvol that touches a CAN socket.
//
// Ownership: open() returns the sole owner; the destructor closes the socket.
// Thread-safety: one thread. Cost: send() is one send(2); receive() is one
// recvmmsg(2) per batch of up to 16 frames plus two vDSO clock reads; both are
// real-time safe (no allocation, no blocking, no logging). open() allocates and
// is for start-up only.
//
// Bus-off: the kernel reports it as an error frame (counted, and handed on so
// that drivers react); configure the interface with automatic restart
// (`ip link set can0 type can restart-ms 100`) so that the controller returns by
// itself and reports "restarted". On vcan a peer can inject these error frames.
//
// Drops: SO_RXQ_OVFL reports the socket's cumulative drop count on the next
// frame queued after a drop, so `dropped` catches up when traffic resumes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "drivers/can/can_bus.hpp"

namespace visvol::can {

struct SocketCanConfig {
  std::string interface;           // network interface name; required, never defaulted
  std::vector<CanFilter> filters;  // empty: every frame; at most 512
  bool error_frames = true;        // receive error frames (bus-off, restarts, bus errors)
  int receive_buffer_bytes = 0;    // SO_RCVBUF, bytes; 0 keeps the kernel default
};

class SocketCanBus final : public CanBus {
 public:
  // Opens and binds the socket. Fails with a Status that names the interface
  // and the cause: Errc::invalid_argument for what the configuration got wrong
  // (no or an overlong name, no such interface, not a CAN interface, too many
  // filters), Errc::io for what the system refused (no SocketCAN in this
  // kernel, permission denied).
  static Result<std::unique_ptr<SocketCanBus>> open(const SocketCanConfig& config);

  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  Errc send(const CanFrame& frame) override;
  std::size_t receive(CanFrame* out, std::size_t capacity) override;
  const CanCounters& counters() const override { return counters_; }

  const std::string& interface() const { return interface_; }

 private:
  struct Batch;  // recvmmsg buffers, allocated once by open()
  SocketCanBus(int fd, std::string interface);

  int fd_;
  std::string interface_;
  CanCounters counters_;
  std::uint32_t kernel_drops_ = 0;  // last SO_RXQ_OVFL value seen
  std::unique_ptr<Batch> batch_;
};

}  // namespace visvol::can
