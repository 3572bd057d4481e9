// JSON from outside (path files, a pack's metadata): parsed with a nesting
// limit. nlohmann parses iteratively, but copying, dumping and comparing a
// value recurse once a level: a 2 MB file of nested brackets overflowed the
// stack of whoever printed it. No file visvol reads needs more than a few
// levels (a QGroundControl plan: 6).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "base/status.hpp"

namespace visvol {

inline constexpr int kMaxJsonDepth = 64;

// The document in `text`, or Errc::invalid_argument "WHAT: not valid JSON:
// ..." (a NUL byte anywhere included) or "WHAT: JSON nested deeper than 64
// levels".
Result<nlohmann::json> parse_json_input(const std::string& text, const std::string& what,
                                        int max_depth = kMaxJsonDepth);

}  // namespace visvol
