// Shared pieces of the renderer tests: a small pack of the paper's two-prism
// terrain, a red-to-blue transfer function whose colours give F_p back from
// any lit pixel, and PNG decoding.
#pragma once

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "../../fields/terrains.hpp"
#include "drivers/render/renderer.hpp"
#include "storage/pack_build.hpp"

namespace visvol::render::testing {

// The paper's Fig. 7 terrain: 64 x 64 posts of 10 m, two 60 m prisms; F_p on
// 32 levels with a 12-post cube. Built in about a second.
inline std::string build_prism_pack(const std::string& stem) {
  const std::string path = ::testing::TempDir() + "/" + stem + "_" + std::to_string(::getpid()) + ".vvp";
  storage::PackBuildParams p;
  p.field.nz = 32;
  p.field.ceiling_m = 150;
  p.field.range_posts = 12;
  p.lod_levels = 1;
  p.tff.band_offset_m = 40;
  p.tff.band_levels = 4;
  p.crs_name = "test frame";
  const Status s = storage::build_pack(fields::testing::two_prisms(64), p, R"({"path":"two prisms"})", path);
  EXPECT_TRUE(s.ok()) << s.message();
  return path;
}

// F = 0 pure red, F = 1 pure blue, linear between: for a pixel of this map
// under any shading, blue / (red + blue) is F. Transparent volume.
inline TransferFunction red_blue() {
  TransferFunction tf;
  tf.colour = {{0.0, 1.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 1.0}};
  tf.opacity = {{0.0, 0.0}};
  return tf;
}

struct Rgb8 {
  int r, g, b;
};

inline Rgb8 rgb_at(const Image& im, double x, double y) {
  const int xi = static_cast<int>(x), yi = static_cast<int>(y);
  const std::uint8_t* p = im.pixel(xi, yi);
  return {p[0], p[1], p[2]};
}

// blue / (red + blue), or -1 for a pixel with neither
inline double blue_fraction(const Rgb8& c) { return c.r + c.b > 0 ? static_cast<double>(c.b) / (c.r + c.b) : -1.0; }

struct Decoded {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes a pixel, top row first
  std::string error;
};

// Decodes a PNG with libpng's simplified API into 8-bit RGB.
inline Decoded decode_png(const std::uint8_t* data, std::size_t size) {
  Decoded d;
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, data, size)) {
    d.error = image.message;
    return d;
  }
  image.format = PNG_FORMAT_RGB;
  d.width = static_cast<int>(image.width);
  d.height = static_cast<int>(image.height);
  d.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, d.rgb.data(), 0, nullptr)) d.error = image.message;
  return d;
}

inline std::vector<std::uint8_t> read_file(const std::string& path) {
  std::vector<std::uint8_t> out;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return out;
  std::uint8_t buffer[65536];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) out.insert(out.end(), buffer, buffer + n);
  std::fclose(f);
  return out;
}

}  // namespace visvol::render::testing
