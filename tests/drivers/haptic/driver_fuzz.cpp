// libFuzzer: arbitrary bus traffic into the codec and the device driver.
// Invariants: decode never crashes and valid frames re-encode identically; the
// driver never commands more than its clamp, and nothing but zero outside
// operational, whatever arrives.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/can/memory_bus.hpp"
#include "drivers/haptic/device_driver.hpp"

namespace {

using namespace visvol;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "invariant broken: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  can::MemoryBus bus(2, 64);
  haptic::DriverConfig config;
  config.node_id = 1;
  auto created = haptic::DeviceDriver::create(config, bus.endpoint(0));
  if (!created.ok()) fail("default configuration rejected");
  haptic::DeviceDriver& driver = created.value();
  std::int64_t now_ns = 1'000'000'000;
  // Each record: 1 byte time step (x 0.1 ms), 2 bytes id, 1 byte length/flags, 8 bytes data.
  constexpr std::size_t kRecord = 12;
  for (std::size_t at = 0; at + kRecord <= size; at += kRecord) {
    const std::uint8_t* r = data + at;
    now_ns += static_cast<std::int64_t>(r[0]) * 100'000;
    bus.set_time_ns(now_ns);
    can::CanFrame f;
    f.id = static_cast<std::uint32_t>(r[1] | (r[2] << 8)) & 0x7FF;
    f.len = static_cast<std::uint8_t>(r[3] % 9);
    f.flags = (r[3] & 0x80) ? can::CanFrame::kError : 0;
    if (f.is_error()) f.id = static_cast<std::uint32_t>(r[1] | (r[2] << 8));
    std::memcpy(f.data.data(), r + 4, 8);

    haptic::Message m;
    if (haptic::decode(f, m) == haptic::DecodeError::ok) {
      const can::CanFrame back = haptic::encode(m);
      if (back.id != f.id || back.len != f.len || std::memcmp(back.data.data(), f.data.data(), f.len) != 0) {
        fail("a valid frame did not re-encode to the same bytes");
      }
    }
    if (f.is_error()) {
      bus.inject(f);
    } else {
      (void)bus.endpoint(1).send(f);
    }
    driver.poll(now_ns);
    const double fx = static_cast<double>(static_cast<std::int8_t>(r[5]));
    (void)driver.command({fx, -2.0 * fx, 0.5}, (r[6] & 1) != 0);
    // What went on the wire: only valid frames, the clamp, zero unless operational.
    can::CanFrame sent[16];
    for (std::size_t n; (n = bus.endpoint(1).receive(sent, 16)) > 0;) {
      for (std::size_t i = 0; i < n; ++i) {
        if (sent[i].is_error()) continue;  // injected ones come back here too
        haptic::Message out;
        if (haptic::decode(sent[i], out) != haptic::DecodeError::ok) fail("the driver sent an invalid frame");
        if (out.kind != haptic::MessageKind::command) continue;
        const double magnitude = haptic::norm3(out.command.force_n);
        if (magnitude > config.max_force_n + 1e-9) fail("force above the clamp");
        if (!driver.operational() && magnitude != 0.0) fail("force outside operational");
      }
    }
  }
  return 0;
}
