#include "io/json_input.hpp"

namespace visvol {

namespace {

// Whether `text` opens arrays and objects deeper than `max_depth` (brackets in
// strings are text), in one pass. Not the parser's depth callback: with one,
// nlohmann 3.11 parses through its callback parser, which searches the
// enclosing container each time an object closes (quadratic: an array of
// 400,000 empty objects, 1.2 MB, took 35 s; a 64 MiB path file, a day).
// Where the text is not JSON this count may differ from the parser's, but
// only past the first error, where the parser stops.
bool nested_deeper_than(const std::string& text, int max_depth) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (depth++ >= max_depth) return true;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return false;
}

}  // namespace

Result<nlohmann::json> parse_json_input(const std::string& text, const std::string& what, int max_depth) {
  // nlohmann takes a NUL byte for the end of the text: what follows it would
  // be read as nothing (a pack's metadata, a path file's features)
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    return invalid_argument(what + ": not valid JSON: a NUL byte at offset " + std::to_string(nul) +
                            " (JSON text has none)");
  }
  if (nested_deeper_than(text, max_depth)) {
    return invalid_argument(what + ": JSON nested deeper than " + std::to_string(max_depth) + " levels");
  }
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return invalid_argument(what + ": not valid JSON: " + e.what());
  }
}

}  // namespace visvol
