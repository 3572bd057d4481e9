// A pack's bytes as two builds of the same terrain and options must share
// them: its build time (metadata `created_utc`) and the two checksums that
// cover it blanked. Used by the tests of split and MPI builds.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "storage/pack_format.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::storage::testing {

inline std::vector<char> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

inline std::vector<char> without_build_time(const std::string& path) {
  std::vector<char> bytes = read_bytes(path);
  const Result<std::shared_ptr<const Pack>> pack = Pack::open(path);
  EXPECT_TRUE(pack.ok()) << path;
  if (!pack.ok()) return {};
  const std::string key = "\"created_utc\": \"";
  const std::string& json = (*pack)->metadata().json;
  const std::size_t at = json.find(key), meta = (*pack)->header().metadata_offset;
  EXPECT_NE(at, std::string::npos) << path;
  if (at == std::string::npos) return {};
  for (std::size_t n = at + key.size(); n < json.size() && json[n] != '"'; ++n) bytes[meta + n] = 'T';
  std::memset(&bytes[offsetof(PackHeader, tables_crc32c)], 0, 4);
  std::memset(&bytes[offsetof(PackHeader, header_crc32c)], 0, 4);
  return bytes;
}

}  // namespace visvol::storage::testing
