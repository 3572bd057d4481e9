// libFuzzer target: the pack reader. Any bytes must open as a valid pack or
// give an error: never a crash, a read outside the mapping, or a hang; mapped
// or inspected, the same verdict. The
// header and table checksums are recomputed first, so mutations reach the
// structural checks behind them rather than stopping at a checksum.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fields/sampler.hpp"
#include "storage/crc32c.hpp"
#include "storage/pack_reader.hpp"

using namespace visvol::storage;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  if (bytes.size() >= sizeof(PackHeader)) {
    PackHeader h;
    std::memcpy(&h, bytes.data(), sizeof h);
    if (h.level_table_offset < bytes.size()) {
      h.tables_crc32c = crc32c(bytes.data() + h.level_table_offset, bytes.size() - h.level_table_offset);
    }
    h.header_crc32c = crc32c(&h, offsetof(PackHeader, header_crc32c));
    std::memcpy(bytes.data(), &h, sizeof h);
  }
  const int fd = memfd_create("pack", MFD_CLOEXEC);
  if (fd < 0) return 0;
  if (write(fd, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
    close(fd);
    return 0;
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  auto pack = Pack::open(path);
  // inspected (nothing mapped, read with pread): the same verdict
  auto inspected = Pack::open(path, PackAccess::inspect);
  if (pack.ok() != inspected.ok() || (!pack.ok() && pack.status().message() != inspected.status().message())) {
    __builtin_trap();
  }
  if (pack.ok()) {
    (void)(*pack)->verify();
    for (int l = 0; l < (*pack)->level_count(); ++l) {
      auto level = PackLevel::open(*pack, l);
      if (!level.ok()) continue;
      // Read what a console would: corners and the middle, every layer.
      const visvol::fields::VolumeGeometry& g = level->geometry();
      const visvol::fields::FieldSampler<PackLevel> s(*level);
      for (int i : {0, g.nx / 2, g.nx - 1}) {
        for (int j : {0, g.ny / 2, g.ny - 1}) {
          const double x = g.origin_x + i * g.spacing_m, y = g.origin_y - j * g.spacing_m;
          const double z = level->post(i, j) + 10.0;
          (void)s.visibility(x, y, z);
          (void)s.gradient(x, y, z);
          (void)s.terrain_force(x, y, z);
          (void)level->area(i, j);
        }
      }
    }
  }
  close(fd);
  return 0;
}
