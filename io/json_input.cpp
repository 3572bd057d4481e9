#include "io/json_input.hpp"

namespace visvol {

namespace {

struct TooDeep {};  // thrown from the parser's callback: stops the parse at once

}  // namespace

Result<nlohmann::json> parse_json_input(const std::string& text, const std::string& what, int max_depth) {
  const auto limit = [max_depth](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
    if (depth >= max_depth &&
        (event == nlohmann::json::parse_event_t::object_start || event == nlohmann::json::parse_event_t::array_start)) {
      throw TooDeep{};
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, limit);
  } catch (const TooDeep&) {
    return invalid_argument(what + ": JSON nested deeper than " + std::to_string(max_depth) + " levels");
  } catch (const nlohmann::json::exception& e) {
    return invalid_argument(what + ": not valid JSON: " + e.what());
  }
}

}  // namespace visvol
