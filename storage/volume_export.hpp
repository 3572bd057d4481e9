// Export of a pack layer as a volume that ParaView, 3D Slicer and VolView open:
// MetaImage (.mhd with the data inline) or VTK image data (.vti, raw appended).
//
// Axes are world axes: x east, y north (rows are written south to north), z up;
// origin and spacing in metres of the pack's CRS. Values are float32, with 3
// components for vector layers. Written under a temporary name and renamed.
// Offline only.
#pragma once

#include <string>
#include <vector>

#include "base/status.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::storage {

enum class ExportLayer { visibility, gradient, height, area, tff };
enum class ExportFormat { mhd, vti };

Result<ExportLayer> parse_export_layer(const std::string& text);
Result<ExportFormat> parse_export_format(const std::string& text);

struct ExportedVolume {
  int nx = 0, ny = 0, nz = 0, components = 1;
  double origin[3] = {0, 0, 0};   // world x, y, z of the first sample (south-west, lowest)
  double spacing[3] = {1, 1, 1};  // metres
  std::string name;               // data array name
  std::vector<float> values;      // x fastest, then y (south to north), then z; components innermost
};

// The layer of one level on its own grid (2D layers have nz = 1; the terrain
// force field is resampled onto the voxel grid as its outward displacement).
ExportedVolume extract_layer(const PackLevel& level, ExportLayer layer);

Status write_volume(const std::string& path, const ExportedVolume& volume, ExportFormat format);

}  // namespace visvol::storage
