#include "storage/tile_copy.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace visvol::storage {

std::uint64_t TileCopy::footprint(std::uint64_t tile_bytes) {
  static const auto page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  return (tile_bytes + page - 1) / page * page;
}

Result<TileCopy> TileCopy::read(const Pack& pack, const TileEntry& tile) {
  TileCopy c;
  c.bytes_ = static_cast<std::size_t>(tile.bytes);
  c.mapped_ = static_cast<std::size_t>(footprint(tile.bytes));
  if (c.mapped_ == 0) return Status(Errc::corrupt, pack.path() + ": " + Pack::describe(tile) + " is empty");
  void* m = ::mmap(nullptr, c.mapped_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) {
    return Status(Errc::resource,
                  pack.path() + ": " + Pack::describe(tile) + ": no memory for a copy: " + std::strerror(errno));
  }
  c.data_ = static_cast<std::uint8_t*>(m);
  VISVOL_RETURN_IF_ERROR(pack.read_tile(tile, c.data_));
  return c;
}

TileCopy::~TileCopy() {
  if (data_ != nullptr) ::munmap(data_, mapped_);  // unlocks it too
}

TileCopy::TileCopy(TileCopy&& other) noexcept { *this = std::move(other); }

TileCopy& TileCopy::operator=(TileCopy&& other) noexcept {
  if (this == &other) return *this;
  if (data_ != nullptr) ::munmap(data_, mapped_);
  data_ = other.data_;
  bytes_ = other.bytes_;
  mapped_ = other.mapped_;
  other.data_ = nullptr;
  other.bytes_ = other.mapped_ = 0;
  return *this;
}

std::string TileCopy::lock() {
  if (data_ == nullptr || ::mlock(data_, mapped_) == 0) return {};
  return std::strerror(errno);
}

}  // namespace visvol::storage
