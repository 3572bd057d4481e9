// MemoryBus: an in-process CAN bus for unit tests and simulations in one thread.
//
// A wire with a fixed number of endpoints. A frame sent by one endpoint reaches
// every other endpoint whose filters accept it (as on a real bus, the sender
// does not hear itself), stamped with the bus time set by the test. Each
// endpoint has a bounded receive queue; a frame that finds it full is dropped
// and counted in that endpoint's `dropped` (as SO_RXQ_OVFL does). inject()
// delivers a frame from outside every endpoint (a controller's error frame).
//
// Ownership: the MemoryBus owns its endpoints; references stay valid for the
// bus's lifetime. Thread-safety: none; one thread drives every endpoint (tests
// step the device and the console in turn, in simulated time). Cost: send() is
// O(endpoints x filters); receive() O(frames). Allocation only in the
// constructor and in set_filters() (start-up); send and receive are real-time safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/can/can_bus.hpp"

namespace visvol::can {

class MemoryBus {
 public:
  class Endpoint final : public CanBus {
   public:
    Errc send(const CanFrame& frame) override;
    std::size_t receive(CanFrame* out, std::size_t capacity) override;
    const CanCounters& counters() const override { return counters_; }

    // Receive filters as SocketCanConfig::filters (empty: every frame) and
    // whether error frames are received.
    void set_filters(std::vector<CanFilter> filters, bool error_frames);
    // Frames waiting in this endpoint's queue.
    std::size_t pending() const { return count_; }

   private:
    friend class MemoryBus;
    Endpoint(MemoryBus* bus, std::size_t queue_capacity);
    bool accepts(const CanFrame& frame) const;
    void deliver(const CanFrame& frame);

    MemoryBus* bus_;
    std::vector<CanFrame> queue_;  // ring of fixed capacity
    std::size_t head_ = 0;         // oldest frame
    std::size_t count_ = 0;
    std::vector<CanFilter> filters_;
    bool error_frames_ = true;
    CanCounters counters_;
  };

  MemoryBus(std::size_t endpoint_count, std::size_t queue_capacity);
  MemoryBus(const MemoryBus&) = delete;
  MemoryBus& operator=(const MemoryBus&) = delete;

  Endpoint& endpoint(std::size_t index) { return *endpoints_.at(index); }
  std::size_t endpoint_count() const { return endpoints_.size(); }

  // The time stamped on frames sent from now on, CLOCK_MONOTONIC-like ns.
  void set_time_ns(std::int64_t now_ns) { now_ns_ = now_ns; }
  std::int64_t time_ns() const { return now_ns_; }

  // Delivers `frame` to every endpoint (as the kernel does with error frames).
  void inject(const CanFrame& frame);

 private:
  void broadcast(const Endpoint* from, const CanFrame& frame);

  std::vector<std::unique_ptr<Endpoint>> endpoints_;
  std::int64_t now_ns_ = 0;
};

}  // namespace visvol::can
