// What path_io.cpp and the .plan reader (plan_file_read.cpp) share: message
// helpers and the reader itself. Not for other callers: path_io.hpp is the
// interface.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "base/status.hpp"
#include "path_io.hpp"

namespace visvol::cli::detail {

// `v` with `decimals` fixed decimals.
std::string fixed(double v, int decimals);
// A number for a message: fixed decimals, or 6 significant digits where that
// would print hundreds of digits (a mistyped 1e308).
std::string shown(double v, int decimals);
// A line for a message: its first 40 characters, unprintable bytes as '?'.
std::string quoted(const std::string& line);
// A JSON value for a message, shortened.
std::string json_brief(const nlohmann::json& j);

// The waypoints of a QGroundControl .plan (a parsed document with a
// fileType), to the pack's CRS.
Result<PathFile> parse_qgc_plan(const nlohmann::json& j, const std::string& path, const std::string& crs_wkt);

}  // namespace visvol::cli::detail
