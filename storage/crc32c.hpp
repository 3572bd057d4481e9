// CRC32C (Castagnoli), as in iSCSI and ext4, through Intel ISA-L (hardware
// accelerated where the CPU has it).
//
// crc32c(data, n) is the standard value (crc32c("123456789") == 0xE3069283);
// pass a previous result as `crc` to continue over more bytes. Thread-safe,
// no allocation.
#pragma once

#include <cstddef>
#include <cstdint>

namespace visvol::storage {

std::uint32_t crc32c(const void* data, std::size_t bytes, std::uint32_t crc = 0);

}  // namespace visvol::storage
