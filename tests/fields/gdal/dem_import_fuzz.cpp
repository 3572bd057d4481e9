// libFuzzer target: DEM import. Any bytes, presented to GDAL as a file of one
// of the formats visvol reads, must give a heightfield or a clear error: never
// a crash, a hang or a leak.
#include <cpl_error.h>
#include <cpl_vsi.h>

#include <cstddef>
#include <cstdint>

#include "fields/gdal/dem_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace visvol::fields;
  static const char* kPath = "/vsimem/fuzz_dem";
  VSILFILE* f = VSIFileFromMemBuffer(kPath, const_cast<GByte*>(data), size, FALSE);
  if (!f) return 0;
  VSIFCloseL(f);
  DemReadOptions options(size > 0 && (data[0] & 1) ? NodataPolicy::fill : NodataPolicy::refuse);
  options.drivers = dem_drivers();
  options.max_posts = std::size_t{1} << 20;  // keep one run small and fast
  const visvol::Result<Heightfield> hf = read_heightfield(kPath, options);
  if (hf.ok()) {
    // What a build does first with an imported DEM.
    const std::vector<float> area = area_factor(*hf);
    if (area.size() != hf->size()) __builtin_trap();
  }
  VSIUnlink(kPath);
  return 0;
}
