#include "drivers/render/png_encoder.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "msg/samples.hpp"
#include "render_test_util.hpp"
#include "tests/support/alloc_counter.hpp"

namespace visvol::render {
namespace {

using testing::decode_png;

// A test card: gradients, a checker and noise (compresses like a picture).
std::vector<std::uint8_t> test_card(int w, int h, std::size_t stride) {
  std::vector<std::uint8_t> px(stride * static_cast<std::size_t>(h), 0xEE);
  std::uint32_t noise = 12345;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      noise = noise * 1664525u + 1013904223u;
      std::uint8_t* p = px.data() + static_cast<std::size_t>(y) * stride + static_cast<std::size_t>(x) * 4;
      p[0] = static_cast<std::uint8_t>(x * 255 / w);
      p[1] = static_cast<std::uint8_t>(static_cast<std::uint32_t>(((x / 8 + y / 8) % 2) * 200) + (noise >> 29));
      p[2] = static_cast<std::uint8_t>(y * 255 / h);
      p[3] = 0x7F;  // alpha is dropped: thumbnails are opaque
    }
  }
  return px;
}

TEST(PngEncoder, RoundTripsExactlyAsRgbWithAnyStride) {
  const int w = 123, h = 77;
  const std::size_t stride = w * 4 + 20;  // padded rows
  const std::vector<std::uint8_t> px = test_card(w, h, stride);
  Result<std::unique_ptr<PngEncoder>> enc = PngEncoder::create(256, 256, 1);
  ASSERT_TRUE(enc.ok()) << enc.status().message();
  std::vector<std::uint8_t> out(PngEncoder::worst_case_bytes(w, h));
  Result<std::size_t> n = (*enc)->encode(px.data(), w, h, stride, out.data(), out.size());
  ASSERT_TRUE(n.ok()) << n.status().message();
  const testing::Decoded d = decode_png(out.data(), *n);
  ASSERT_TRUE(d.error.empty()) << d.error;
  ASSERT_EQ(d.width, w);
  ASSERT_EQ(d.height, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(d.rgb[static_cast<std::size_t>((y * w + x) * 3 + c)],
                  px[static_cast<std::size_t>(y) * stride + static_cast<std::size_t>(x * 4 + c)])
            << "pixel (" << x << ", " << y << ") channel " << c;
      }
    }
  }
}

TEST(PngEncoder, HigherLevelsAreSmallerAndLevelZeroIsStored) {
  const int w = 256, h = 256;
  const std::vector<std::uint8_t> px = test_card(w, h, w * 4);
  std::vector<std::uint8_t> out(PngEncoder::worst_case_bytes(w, h));
  std::size_t size[10] = {};
  for (int level : {0, 1, 6, 9}) {
    Result<std::unique_ptr<PngEncoder>> enc = PngEncoder::create(w, h, level);
    ASSERT_TRUE(enc.ok());
    Result<std::size_t> n = (*enc)->encode(px.data(), w, h, w * 4, out.data(), out.size());
    ASSERT_TRUE(n.ok()) << n.status().message();
    size[level] = *n;
    EXPECT_EQ((*enc)->compression_level(), level);
    EXPECT_LE((*enc)->arena_used_bytes(), (*enc)->arena_bytes());
  }
  // level 0 stores the scanlines: at least 3 bytes a pixel
  EXPECT_GE(size[0], static_cast<std::size_t>(w * h * 3));
  EXPECT_LE(size[0], PngEncoder::worst_case_bytes(w, h));
  EXPECT_LT(size[1], size[0]);
  EXPECT_LT(size[6], size[1]);
  EXPECT_LE(size[9], size[6]);
}

TEST(PngEncoder, SaysWhenTheOutputDoesNotFitAndRecovers) {
  const int w = 200, h = 150;
  const std::vector<std::uint8_t> px = test_card(w, h, w * 4);
  Result<std::unique_ptr<PngEncoder>> enc = PngEncoder::create(w, h, 1);
  ASSERT_TRUE(enc.ok());
  std::vector<std::uint8_t> out(PngEncoder::worst_case_bytes(w, h));
  Result<std::size_t> small = (*enc)->encode(px.data(), w, h, w * 4, out.data(), 1000);
  ASSERT_FALSE(small.ok());
  EXPECT_EQ(small.status().code(), Errc::resource);
  EXPECT_NE(small.status().message().find("does not fit the 1000-byte output buffer"), std::string::npos)
      << small.status().message();
  // the encoder is fine afterwards
  Result<std::size_t> n = (*enc)->encode(px.data(), w, h, w * 4, out.data(), out.size());
  ASSERT_TRUE(n.ok()) << n.status().message();
  EXPECT_TRUE(decode_png(out.data(), *n).error.empty());
}

TEST(PngEncoder, RefusesBadArguments) {
  EXPECT_FALSE(PngEncoder::create(0, 10, 1).ok());
  EXPECT_FALSE(PngEncoder::create(10, 10, 10).ok());
  EXPECT_FALSE(PngEncoder::create(10, 10, -1).ok());
  Result<std::unique_ptr<PngEncoder>> enc = PngEncoder::create(64, 64, 1);
  ASSERT_TRUE(enc.ok());
  std::vector<std::uint8_t> px(65 * 65 * 4), out(PngEncoder::worst_case_bytes(65, 65));
  Result<std::size_t> big = (*enc)->encode(px.data(), 65, 10, 65 * 4, out.data(), out.size());
  ASSERT_FALSE(big.ok());
  EXPECT_NE(big.status().message().find("65 x 10 is outside the encoder's 1..64 x 1..64"), std::string::npos)
      << big.status().message();
  Result<std::size_t> stride = (*enc)->encode(px.data(), 10, 10, 39, out.data(), out.size());
  ASSERT_FALSE(stride.ok());
  EXPECT_NE(stride.status().message().find("stride 39"), std::string::npos);
  EXPECT_FALSE((*enc)->encode(nullptr, 10, 10, 40, out.data(), out.size()).ok());
}

TEST(PngEncoder, AllocatesNothingPerImageAndFitsAThumbnailSample) {
  const int w = 256, h = 256;
  const std::vector<std::uint8_t> px = test_card(w, h, w * 4);
  Result<std::unique_ptr<PngEncoder>> enc = PngEncoder::create(w, h, 6);
  ASSERT_TRUE(enc.ok());
  auto sample = std::make_unique<msg::ThumbnailSample>();
  // libpng and zlib allocate from the encoder's arena (its high-water mark
  // holds zlib's deflate state, about 260 KiB), and operator new is never reached
  const std::uint64_t before = visvol::testing::allocation_count();
  std::size_t bytes = 0;
  for (int i = 0; i < 20; ++i) {
    Result<std::size_t> n = (*enc)->encode(px.data(), w, h, w * 4, sample->png, sizeof sample->png);
    ASSERT_TRUE(n.ok()) << n.status().message();
    bytes = *n;
  }
  EXPECT_EQ(visvol::testing::allocation_count(), before);
  EXPECT_GT((*enc)->arena_used_bytes(), 200u * 1024);  // zlib's state was in it
  sample->png_size_bytes = static_cast<std::uint32_t>(bytes);
  EXPECT_TRUE(decode_png(sample->png, sample->png_size_bytes).error.empty());
}

}  // namespace
}  // namespace visvol::render
