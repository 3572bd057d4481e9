// PNG encoding through libpng into a caller's buffer, with no heap allocation
// per image: libpng and zlib allocate from an arena reserved at create() and
// rewound after every image.
//
// Output: 8-bit RGB (the alpha channel of the input is dropped: thumbnails are
// opaque), no interlacing, zlib compression level 0..9 (1 is about 3x cheaper
// than 6 at 1024x768 and a little larger), filter SUB at levels 0..3 (cheap),
// libpng's adaptive choice above.
//
// Ownership: the encoder owns its arena; encode() reads the caller's pixels
// and writes the caller's buffer. Not thread-safe (one image at a time); not
// real-time safe (tens of milliseconds), but allocation-free after create().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "base/status.hpp"

namespace visvol::render {

class PngEncoder {
 public:
  // Sizes up to max_width_px x max_height_px; compression_level 0..9.
  static Result<std::unique_ptr<PngEncoder>> create(int max_width_px, int max_height_px, int compression_level);
  ~PngEncoder();
  PngEncoder(const PngEncoder&) = delete;
  PngEncoder& operator=(const PngEncoder&) = delete;

  // Encodes `rgba` (width x height pixels of 4 bytes, top row first, rows
  // `stride_bytes` apart) into out[0, capacity_bytes). Returns the PNG's size
  // in bytes. Fails (nothing usable in `out`) when the image is larger than
  // the maximum, the PNG does not fit `capacity_bytes`, or libpng reports an
  // error; the message says which. No allocation on success.
  Result<std::size_t> encode(const std::uint8_t* rgba, int width_px, int height_px, std::size_t stride_bytes,
                             std::uint8_t* out, std::size_t capacity_bytes);

  int compression_level() const { return level_; }
  // Arena bytes the last image used and the arena's size (for tests).
  std::size_t arena_used_bytes() const { return arena_high_water_; }
  std::size_t arena_bytes() const { return arena_size_; }

  // A safe output capacity for any image up to width x height at any level:
  // raw scanlines plus zlib's worst-case overhead and the PNG chunks.
  static std::size_t worst_case_bytes(int width_px, int height_px);

  // Internal state reached from libpng's C callbacks.
  struct Context;

 private:
  PngEncoder() = default;

  int max_width_ = 0, max_height_ = 0, level_ = 1;
  std::unique_ptr<std::uint8_t[]> arena_;
  std::size_t arena_size_ = 0, arena_high_water_ = 0;
  std::unique_ptr<const std::uint8_t*[]> rows_;  // row pointers, one per row
  std::unique_ptr<Context> context_;
};

}  // namespace visvol::render
