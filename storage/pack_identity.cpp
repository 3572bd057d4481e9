#include "storage/pack_identity.hpp"

#include <cctype>

namespace visvol::storage {

std::string pack_id_from_path(const std::string& pack_path) {
  std::string name = pack_path.substr(pack_path.find_last_of('/') + 1);
  const std::size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.erase(dot);
  for (char& c : name) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  if (name.empty()) name = "pack";
  if (name.size() > 63) name.resize(63);
  return name;
}

std::string epsg_from_wkt(const std::string& wkt) {
  // Walk the brackets; remember the last AUTHORITY/ID opened at depth 1 (a
  // direct child of the CRS node).
  int depth = 0;
  std::size_t last = std::string::npos;
  bool in_string = false;
  for (std::size_t i = 0; i < wkt.size(); ++i) {
    const char c = wkt[i];
    if (c == '"') in_string = !in_string;
    if (in_string) continue;
    if (c == '[' || c == '(') {
      ++depth;
      if (depth == 2) {
        std::size_t k = i;
        while (k > 0 && std::isalpha(static_cast<unsigned char>(wkt[k - 1]))) --k;
        const std::string keyword = wkt.substr(k, i - k);
        if (keyword == "AUTHORITY" || keyword == "ID") last = i + 1;
      }
    } else if (c == ']' || c == ')') {
      --depth;
    }
  }
  if (last == std::string::npos) return {};
  // AUTHORITY["EPSG","26710"] or ID["EPSG",26710]
  const std::string rest = wkt.substr(last);
  if (rest.compare(0, 6, "\"EPSG\"") != 0) return {};
  std::size_t p = 6;
  while (p < rest.size() && (rest[p] == ',' || rest[p] == ' ' || rest[p] == '"')) ++p;
  std::string code;
  while (p < rest.size() && std::isdigit(static_cast<unsigned char>(rest[p]))) code += rest[p++];
  return code.empty() ? std::string() : "EPSG:" + code;
}

}  // namespace visvol::storage
