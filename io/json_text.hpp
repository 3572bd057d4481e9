// JSON text for outputs (summaries, reports, metadata, --json). A string that
// is not valid UTF-8 (a file name from the command line, a crafted pack's
// metadata) is written with U+FFFD in place of its bad bytes: nlohmann's
// default is to throw, which aborted the console before its summary.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace visvol {

// `indent` as nlohmann's dump(): -1 on one line, n spaces a level otherwise.
inline std::string json_text(const nlohmann::json& j, int indent = -1) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace visvol
