#include "storage/crc32c.hpp"

#include <isa-l/crc.h>

#include <climits>

namespace visvol::storage {

std::uint32_t crc32c(const void* data, std::size_t bytes, std::uint32_t crc) {
  // ISA-L works on the raw (uninverted) register and takes int lengths.
  unsigned int raw = ~crc;
  const unsigned char* p = static_cast<const unsigned char*>(data);
  while (bytes > 0) {
    const std::size_t chunk = bytes > static_cast<std::size_t>(INT_MAX) ? static_cast<std::size_t>(1) << 30 : bytes;
    raw = crc32_iscsi(const_cast<unsigned char*>(p), static_cast<int>(chunk), raw);
    p += chunk;
    bytes -= chunk;
  }
  return ~raw;
}

}  // namespace visvol::storage
