// How a pack is named to the outside: the id subscribers and commands use,
// and the EPSG code of its CRS for the terrain topic.
//
// Thread-safety: pure functions. Cost: O(text). Not real-time (strings).
#pragma once

#include <string>

namespace visvol::storage {

// The pack file's name without directory and extension, characters outside
// [A-Za-z0-9._-] replaced by '_', at most 63 characters; "pack" if nothing is
// left.
std::string pack_id_from_path(const std::string& pack_path);

// "EPSG:<code>" when the WKT (WKT1 AUTHORITY or WKT2 ID) names an EPSG code
// for the whole CRS, empty otherwise. The whole CRS's identifier is the last
// one at the outermost level of the text.
std::string epsg_from_wkt(const std::string& wkt);

}  // namespace visvol::storage
