#include "storage/volume_export.hpp"

#include <cstdint>
#include <fstream>
#include <sstream>

#include "fields/sampler.hpp"
#include "io/atomic_file.hpp"

namespace visvol::storage {

Result<ExportLayer> parse_export_layer(const std::string& t) {
  if (t == "visibility") return ExportLayer::visibility;
  if (t == "gradient") return ExportLayer::gradient;
  if (t == "height") return ExportLayer::height;
  if (t == "area") return ExportLayer::area;
  if (t == "tff") return ExportLayer::tff;
  return invalid_argument("layer '" + t + "' is not one of visibility, gradient, height, area, tff");
}

Result<ExportFormat> parse_export_format(const std::string& t) {
  if (t == "mhd") return ExportFormat::mhd;
  if (t == "vti") return ExportFormat::vti;
  return invalid_argument("format '" + t + "' is not one of mhd, vti");
}

ExportedVolume extract_layer(const PackLevel& level, ExportLayer layer) {
  const fields::VolumeGeometry& g = level.geometry();
  ExportedVolume v;
  v.nx = g.nx;
  v.ny = g.ny;
  const bool flat = layer == ExportLayer::height || layer == ExportLayer::area;
  v.nz = flat ? 1 : g.nz;
  v.components = (layer == ExportLayer::gradient || layer == ExportLayer::tff) ? 3 : 1;
  // Row ny - 1 is the southernmost: it becomes y index 0.
  v.origin[0] = g.origin_x;
  v.origin[1] = g.origin_y - (g.ny - 1) * g.spacing_m;
  v.origin[2] = flat ? 0.0 : g.z0_m;
  v.spacing[0] = v.spacing[1] = g.spacing_m;
  v.spacing[2] = flat ? 1.0 : g.dz_m;
  const char* names[] = {"visibility", "visibility_gradient_per_m", "height_m", "area_factor",
                         "terrain_displacement_m"};
  v.name = names[static_cast<int>(layer)];
  v.values.resize(static_cast<std::size_t>(v.nx) * static_cast<std::size_t>(v.ny) * static_cast<std::size_t>(v.nz) *
                  static_cast<std::size_t>(v.components));
  const fields::FieldSampler<PackLevel> sampler(level);
  std::size_t n = 0;
  for (int k = 0; k < v.nz; ++k) {
    for (int y = 0; y < v.ny; ++y) {
      const int j = g.ny - 1 - y;
      for (int i = 0; i < v.nx; ++i) {
        switch (layer) {
          case ExportLayer::visibility: v.values[n++] = level.voxel(i, j, k); break;
          case ExportLayer::height: v.values[n++] = level.post(i, j); break;
          case ExportLayer::area: v.values[n++] = level.area(i, j); break;
          case ExportLayer::gradient: {
            const Eigen::Vector3d d = sampler.voxel_gradient(i, j, k);
            for (int c = 0; c < 3; ++c) v.values[n++] = static_cast<float>(d[c]);
            break;
          }
          case ExportLayer::tff: {
            // Outside the band there is no force: zero.
            const double z = g.z_of(k);
            const double above = z - level.post(i, j);
            fields::TffSample s;
            if (std::abs(above) <= level.tff_params().band_offset_m) {
              s = sampler.terrain_force(g.origin_x + i * g.spacing_m, g.origin_y - j * g.spacing_m, z);
            }
            v.values[n++] = s.dx_m;
            v.values[n++] = s.dy_m;
            v.values[n++] = s.dz_m;
            break;
          }
        }
      }
    }
  }
  return v;
}

namespace {

std::string mhd_header(const ExportedVolume& v) {
  std::ostringstream h;
  h.precision(17);
  h << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
    << "CompressedData = False\n"
    << "TransformMatrix = 1 0 0 0 1 0 0 0 1\n"
    << "Offset = " << v.origin[0] << " " << v.origin[1] << " " << v.origin[2] << "\n"
    << "AnatomicalOrientation = RAI\n"
    << "ElementSpacing = " << v.spacing[0] << " " << v.spacing[1] << " " << v.spacing[2] << "\n"
    << "DimSize = " << v.nx << " " << v.ny << " " << v.nz << "\n";
  if (v.components > 1) h << "ElementNumberOfChannels = " << v.components << "\n";
  h << "ElementType = MET_FLOAT\nElementDataFile = LOCAL\n";
  return h.str();
}

std::string vti_header(const ExportedVolume& v) {
  std::ostringstream h;
  h.precision(17);
  h << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    << "  <ImageData WholeExtent=\"0 " << v.nx - 1 << " 0 " << v.ny - 1 << " 0 " << v.nz - 1 << "\" Origin=\""
    << v.origin[0] << " " << v.origin[1] << " " << v.origin[2] << "\" Spacing=\"" << v.spacing[0] << " " << v.spacing[1]
    << " " << v.spacing[2] << "\">\n"
    << "    <Piece Extent=\"0 " << v.nx - 1 << " 0 " << v.ny - 1 << " 0 " << v.nz - 1 << "\">\n"
    << "      <PointData Scalars=\"" << v.name << "\">\n"
    << "        <DataArray type=\"Float32\" Name=\"" << v.name << "\" NumberOfComponents=\"" << v.components
    << "\" format=\"appended\" offset=\"0\"/>\n"
    << "      </PointData>\n    </Piece>\n  </ImageData>\n"
    << "  <AppendedData encoding=\"raw\">\n   _";
  return h.str();
}

}  // namespace

Status write_volume(const std::string& path, const ExportedVolume& v, ExportFormat format) {
  Result<OutputFile> out = OutputFile::create(path);
  if (!out.ok()) return out.status();
  const std::uint64_t bytes = v.values.size() * sizeof(float);
  const auto write_text = [&](const std::string& text) { return out->write(text.data(), text.size()); };
  if (format == ExportFormat::mhd) {
    VISVOL_RETURN_IF_ERROR(write_text(mhd_header(v)));
    VISVOL_RETURN_IF_ERROR(out->write(v.values.data(), static_cast<std::size_t>(bytes)));
  } else {
    VISVOL_RETURN_IF_ERROR(write_text(vti_header(v)));
    VISVOL_RETURN_IF_ERROR(out->write(&bytes, sizeof bytes));
    VISVOL_RETURN_IF_ERROR(out->write(v.values.data(), static_cast<std::size_t>(bytes)));
    VISVOL_RETURN_IF_ERROR(write_text("\n  </AppendedData>\n</VTKFile>\n"));
  }
  return out->commit();
}

}  // namespace visvol::storage
