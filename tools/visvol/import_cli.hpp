// The terrain import options every command that reads a DEM shares.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "fields/gdal/dem_import.hpp"

namespace visvol::cli {

struct ImportCli {
  bool fill_nodata = false;
  std::string t_srs;
  std::string assume_srs;
  double spacing_m = 0;
  std::vector<double> crop;  // xmin ymin xmax ymax
  std::string resampling = "bilinear";
  // set by a command, not an option: 0 keeps the library's limit
  std::size_t max_posts = 0;
  std::string max_posts_reason;
};

void add_import_options(CLI::App* app, ImportCli& o);

// The library's import options for the command-line ones.
fields::ImportOptions import_options(const ImportCli& o);

// Imports `path` with the options, naming the file in errors.
Result<fields::Heightfield> import(const std::string& path, const ImportCli& o, fields::ImportReport* report);

// A JSON object describing the source and how it was imported (for pack
// metadata): path, SHA-256, driver, CRS, options.
std::string source_json(const std::string& path, const ImportCli& o, const fields::ImportReport& report);

// SHA-256 of a file as lowercase hex, or an error naming it.
Result<std::string> sha256_file(const std::string& path);

}  // namespace visvol::cli
