// Files that appear whole or not at all.
//
// Writers write to temp_path_for(path), then commit_file(): fsync the data,
// rename over the destination, fsync the directory. A crash or a kill before the
// rename leaves the old file (or none) and a stray temporary, never a torn file.
//
// Not real-time safe (blocking I/O).
#pragma once

#include <string>

#include "rt/base/status.hpp"

namespace visvol {

// A temporary name next to `path` (same directory, so rename is atomic), unique
// per process.
std::string temp_path_for(const std::string& path);

// Makes `temp_path` durable and renames it to `path`. On failure the temporary
// is removed and `path` is untouched.
Status commit_file(const std::string& temp_path, const std::string& path);

// Removes a temporary left by a failed write (errors ignored).
void discard_file(const std::string& temp_path);

// Writes a whole file that way: `path` holds the old content or `bytes`,
// never part of them.
Status write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace visvol
