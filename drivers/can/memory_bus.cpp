#include "drivers/can/memory_bus.hpp"

#include <utility>

namespace visvol::can {

MemoryBus::Endpoint::Endpoint(MemoryBus* bus, std::size_t queue_capacity) : bus_(bus), queue_(queue_capacity) {}

void MemoryBus::Endpoint::set_filters(std::vector<CanFilter> filters, bool error_frames) {
  filters_ = std::move(filters);
  error_frames_ = error_frames;
}

bool MemoryBus::Endpoint::accepts(const CanFrame& frame) const {
  if (frame.is_error()) return error_frames_;
  if (filters_.empty()) return true;
  if (!frame.is_standard_data()) return false;  // filters pass standard data frames only
  for (const CanFilter& f : filters_) {
    if (((frame.id ^ f.id) & f.mask & kStandardIdMask) == 0) return true;
  }
  return false;
}

void MemoryBus::Endpoint::deliver(const CanFrame& frame) {
  if (!accepts(frame)) return;
  if (count_ == queue_.size()) {
    ++counters_.dropped;
    return;
  }
  CanFrame& slot = queue_[(head_ + count_) % queue_.size()];
  slot = frame;
  slot.timestamp_ns = bus_->now_ns_;
  ++count_;
}

Errc MemoryBus::Endpoint::send(const CanFrame& frame) {
  if (frame.len > kMaxDataBytes) {
    ++counters_.send_failed;
    return Errc::invalid_argument;
  }
  ++counters_.sent;
  bus_->broadcast(this, frame);
  return Errc::ok;
}

std::size_t MemoryBus::Endpoint::receive(CanFrame* out, std::size_t capacity) {
  std::size_t got = 0;
  while (got < capacity && count_ > 0) {
    out[got] = queue_[head_];
    if (out[got].is_error()) count_error_frame(counters_, out[got]);
    head_ = (head_ + 1) % queue_.size();
    --count_;
    ++got;
  }
  counters_.received += got;
  return got;
}

MemoryBus::MemoryBus(std::size_t endpoint_count, std::size_t queue_capacity) {
  endpoints_.reserve(endpoint_count);
  for (std::size_t i = 0; i < endpoint_count; ++i) {
    endpoints_.push_back(std::unique_ptr<Endpoint>(new Endpoint(this, queue_capacity)));
  }
}

void MemoryBus::broadcast(const Endpoint* from, const CanFrame& frame) {
  for (const auto& e : endpoints_) {
    if (e.get() != from) e->deliver(frame);
  }
}

void MemoryBus::inject(const CanFrame& frame) { broadcast(nullptr, frame); }

}  // namespace visvol::can
