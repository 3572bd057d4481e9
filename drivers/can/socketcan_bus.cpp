// The only file in visvol that touches a CAN socket.
#include "drivers/can/socketcan_bus.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace visvol::can {

// The error constants in can_frame.hpp are the kernel's.
static_assert(err::kTxTimeout == CAN_ERR_TX_TIMEOUT && err::kLostArbitration == CAN_ERR_LOSTARB &&
              err::kController == CAN_ERR_CRTL && err::kProtocol == CAN_ERR_PROT && err::kTransceiver == CAN_ERR_TRX &&
              err::kNoAck == CAN_ERR_ACK && err::kBusOff == CAN_ERR_BUSOFF && err::kBusError == CAN_ERR_BUSERROR &&
              err::kRestarted == CAN_ERR_RESTARTED && err::kCounters == CAN_ERR_CNT &&
              err::kAllClasses == CAN_ERR_MASK);
static_assert(err::kCtrlRxOverflow == CAN_ERR_CRTL_RX_OVERFLOW && err::kCtrlTxOverflow == CAN_ERR_CRTL_TX_OVERFLOW &&
              err::kCtrlRxWarning == CAN_ERR_CRTL_RX_WARNING && err::kCtrlTxWarning == CAN_ERR_CRTL_TX_WARNING &&
              err::kCtrlRxPassive == CAN_ERR_CRTL_RX_PASSIVE && err::kCtrlTxPassive == CAN_ERR_CRTL_TX_PASSIVE &&
              err::kCtrlActive == CAN_ERR_CRTL_ACTIVE);
static_assert(kMaxDataBytes == CAN_MAX_DLEN && kStandardIdMask == CAN_SFF_MASK && kExtendedIdMask == CAN_EFF_MASK);
static_assert(sizeof(can_frame) == CAN_MTU && sizeof(can_frame) == 16);

namespace {

constexpr unsigned kBatchFrames = 16;
// Room for a timestamp and a drop count per message.
constexpr std::size_t kControlBytes = CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t));

std::int64_t clock_ns(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::string errno_text(int e) { return std::strerror(e); }

// A Status that names the interface and the step that failed.
Status open_error(const std::string& interface, const std::string& step, int e) {
  std::string message = "CAN interface '" + interface + "': " + step + ": " + errno_text(e);
  if (e == EAFNOSUPPORT) {
    message += " (this kernel has no SocketCAN: load the can and can-raw modules)";
  } else if (e == EPERM || e == EACCES) {
    message += " (needs CAP_NET_RAW)";
  }
  return io_error(std::move(message));
}

can_frame to_kernel(const CanFrame& frame) {
  can_frame out{};
  if (frame.is_error()) {
    out.can_id = (frame.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  } else if ((frame.flags & CanFrame::kExtended) != 0) {
    out.can_id = (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG;
  } else {
    out.can_id = frame.id & CAN_SFF_MASK;
  }
  if ((frame.flags & CanFrame::kRemote) != 0) out.can_id |= CAN_RTR_FLAG;
  out.len = frame.len;
  std::memcpy(out.data, frame.data.data(), frame.len);
  return out;
}

// False for anything that is not one whole classic frame.
bool from_kernel(const can_frame& in, CanFrame& out) {
  if (in.len > CAN_MAX_DLEN) return false;
  out.flags = 0;
  if ((in.can_id & CAN_ERR_FLAG) != 0) {
    out.flags = CanFrame::kError;
    out.id = in.can_id & CAN_ERR_MASK;
  } else if ((in.can_id & CAN_EFF_FLAG) != 0) {
    out.flags = CanFrame::kExtended;
    out.id = in.can_id & CAN_EFF_MASK;
  } else {
    out.id = in.can_id & CAN_SFF_MASK;
  }
  if ((in.can_id & CAN_RTR_FLAG) != 0) out.flags |= CanFrame::kRemote;
  out.len = in.len;
  out.data = {};
  std::memcpy(out.data.data(), in.data, in.len);
  return true;
}

}  // namespace

struct SocketCanBus::Batch {
  std::array<can_frame, kBatchFrames> frames{};
  std::array<iovec, kBatchFrames> iov{};
  std::array<mmsghdr, kBatchFrames> msgs{};
  alignas(cmsghdr) std::array<std::array<unsigned char, kControlBytes>, kBatchFrames> control{};

  Batch() {
    for (unsigned i = 0; i < kBatchFrames; ++i) {
      iov[i].iov_base = &frames[i];
      iov[i].iov_len = sizeof(can_frame);
      msgs[i].msg_hdr.msg_iov = &iov[i];
      msgs[i].msg_hdr.msg_iovlen = 1;
      msgs[i].msg_hdr.msg_control = control[i].data();
    }
  }
  void rearm(unsigned count) {
    for (unsigned i = 0; i < count; ++i) {
      msgs[i].msg_hdr.msg_controllen = kControlBytes;
      msgs[i].msg_hdr.msg_flags = 0;
      msgs[i].msg_len = 0;
    }
  }
};

SocketCanBus::SocketCanBus(int fd, std::string interface)
    : fd_(fd), interface_(std::move(interface)), batch_(std::make_unique<Batch>()) {}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) ::close(fd_);
}

Result<std::unique_ptr<SocketCanBus>> SocketCanBus::open(const SocketCanConfig& config) {
  const std::string& name = config.interface;
  if (name.empty()) return invalid_argument("CAN interface: no name given");
  if (name.size() >= IFNAMSIZ) {
    return invalid_argument("CAN interface '" + name + "': name longer than " + std::to_string(IFNAMSIZ - 1) +
                            " characters");
  }
  if (config.filters.size() > CAN_RAW_FILTER_MAX) {
    return invalid_argument("CAN interface '" + name + "': " + std::to_string(config.filters.size()) +
                            " filters, at most " + std::to_string(CAN_RAW_FILTER_MAX));
  }
  if (config.receive_buffer_bytes < 0) {
    return invalid_argument("CAN interface '" + name + "': negative receive buffer size");
  }

  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) return open_error(name, "socket(PF_CAN)", errno);
  std::unique_ptr<SocketCanBus> bus(new SocketCanBus(fd, name));

  const unsigned index = ::if_nametoindex(name.c_str());
  if (index == 0) return invalid_argument("CAN interface '" + name + "': no such network interface");

  // Filters: standard data frames only (the EFF and RTR bits take part in the match).
  std::vector<can_filter> filters;
  filters.reserve(config.filters.size());
  for (const CanFilter& f : config.filters) {
    filters.push_back({f.id & CAN_SFF_MASK, (f.mask & CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG});
  }
  if (!config.filters.empty() && ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                                              static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0) {
    return open_error(name, "setting receive filters", errno);
  }
  const can_err_mask_t err_mask = config.error_frames ? CAN_ERR_MASK : 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof(err_mask)) != 0) {
    return open_error(name, "enabling error frames", errno);
  }
  const int one = 1;
  if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one)) != 0) {
    return open_error(name, "enabling SO_RXQ_OVFL", errno);
  }
  if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one)) != 0) {
    return open_error(name, "enabling SO_TIMESTAMPNS", errno);
  }
  if (config.receive_buffer_bytes > 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &config.receive_buffer_bytes, sizeof(config.receive_buffer_bytes)) != 0) {
    return open_error(name, "setting SO_RCVBUF", errno);
  }

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int e = errno;
    if (e == ENODEV) return invalid_argument("CAN interface '" + name + "': not a CAN interface");
    return open_error(name, "bind", e);
  }
  return Result<std::unique_ptr<SocketCanBus>>(std::move(bus));
}

Errc SocketCanBus::send(const CanFrame& frame) {
  if (frame.len > kMaxDataBytes) {
    ++counters_.send_failed;
    return Errc::invalid_argument;
  }
  const can_frame out = to_kernel(frame);
  const ssize_t n = ::send(fd_, &out, sizeof(out), MSG_DONTWAIT);
  if (n == static_cast<ssize_t>(sizeof(out))) {
    ++counters_.sent;
    return Errc::ok;
  }
  ++counters_.send_failed;
  if (n >= 0) return Errc::io;
  return (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS) ? Errc::resource : Errc::io;
}

std::size_t SocketCanBus::receive(CanFrame* out, std::size_t capacity) {
  Batch& b = *batch_;
  std::size_t got = 0;
  bool have_offset = false;
  std::int64_t mono_now_ns = 0, real_to_mono_ns = 0;
  while (got < capacity) {
    const auto want = static_cast<unsigned>(std::min<std::size_t>(capacity - got, kBatchFrames));
    b.rearm(want);
    const int n = ::recvmmsg(fd_, b.msgs.data(), want, MSG_DONTWAIT, nullptr);
    if (n <= 0) {
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        ++counters_.receive_errors;
      }
      break;
    }
    if (!have_offset) {
      // Kernel timestamps are CLOCK_REALTIME; the console runs on CLOCK_MONOTONIC.
      mono_now_ns = clock_ns(CLOCK_MONOTONIC);
      real_to_mono_ns = mono_now_ns - clock_ns(CLOCK_REALTIME);
      have_offset = true;
    }
    for (int i = 0; i < n; ++i) {
      const mmsghdr& m = b.msgs[static_cast<unsigned>(i)];
      CanFrame& frame = out[got];
      if (m.msg_len != sizeof(can_frame) || (m.msg_hdr.msg_flags & MSG_TRUNC) != 0 ||
          !from_kernel(b.frames[static_cast<unsigned>(i)], frame)) {
        ++counters_.malformed;
        continue;
      }
      frame.timestamp_ns = mono_now_ns;
      for (cmsghdr* c = CMSG_FIRSTHDR(&m.msg_hdr); c != nullptr; c = CMSG_NXTHDR(const_cast<msghdr*>(&m.msg_hdr), c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SO_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
          const std::int64_t real_ns = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
          frame.timestamp_ns = std::min(real_ns + real_to_mono_ns, mono_now_ns);
        } else if (c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t drops = 0;
          std::memcpy(&drops, CMSG_DATA(c), sizeof(drops));
          counters_.dropped += static_cast<std::uint32_t>(drops - kernel_drops_);  // wraps
          kernel_drops_ = drops;
        }
      }
      if (frame.is_error()) count_error_frame(counters_, frame);
      ++counters_.received;
      ++got;
    }
    if (static_cast<unsigned>(n) < want) break;
  }
  return got;
}

}  // namespace visvol::can
