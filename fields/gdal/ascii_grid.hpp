// Internal to fields/gdal: the cells of an ESRI (AAIGrid) or GRASS ASCII grid
// checked as text. GDAL's readers of these formats turn a cell that is not a
// number ("abc", "1.2.3") into 0 without a warning, so a typo becomes a 0 m
// post; this scan refuses such a file before GDAL reads it.
#pragma once

#include <string>

#include "base/status.hpp"

namespace visvol::fields::gdal {

// True for the GDAL drivers whose cells are text (AAIGrid, GRASSASCIIGrid).
bool is_ascii_grid_driver(const std::string& driver);

// Reads `path` (a plain or /vsi path) once, skips the header lines (the
// formats' keywords: ncols, nrows, xllcorner, ..., north:, rows:, null:, ...)
// and checks that exactly nx * ny cells follow, each a number or the file's
// declared nodata/null token. The first bad cell is named by column and row.
// Cost: one pass over the file, constant memory.
Status check_ascii_grid_cells(const std::string& path, int nx, int ny);

}  // namespace visvol::fields::gdal
