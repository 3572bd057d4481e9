#include "drivers/render/png_encoder.hpp"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>

namespace visvol::render {

// What libpng's callbacks reach through their user pointers: the arena, the
// output buffer and the first error. Plain data, reset before every image.
struct PngEncoder::Context {
  std::uint8_t* arena = nullptr;
  std::size_t arena_size = 0;
  std::size_t arena_offset = 0;
  bool arena_exhausted = false;
  std::uint8_t* out = nullptr;
  std::size_t out_capacity = 0;
  std::size_t out_size = 0;
  bool out_full = false;
  char error[160] = {};
};

namespace {

constexpr std::size_t kArenaAlign = 16;
// zlib's deflate state at windowBits 15, memLevel 8 is about 268 KiB; libpng
// adds its structs and a few filter rows. The rest is margin.
constexpr std::size_t kArenaFixedBytes = 768 * 1024;

using Context = PngEncoder::Context;

Context* context_of_mem(png_structp png) { return static_cast<Context*>(png_get_mem_ptr(png)); }

// Bump allocation; frees are no-ops and the arena is rewound per image.
png_voidp on_malloc(png_structp png, png_alloc_size_t size) {
  Context* c = context_of_mem(png);
  const std::size_t start = (c->arena_offset + kArenaAlign - 1) & ~(kArenaAlign - 1);
  if (size > c->arena_size || start > c->arena_size - size) {
    c->arena_exhausted = true;
    return nullptr;
  }
  c->arena_offset = start + size;
  return c->arena + start;
}

void on_free(png_structp, png_voidp) {}

void on_write(png_structp png, png_bytep data, png_size_t length) {
  Context* c = static_cast<Context*>(png_get_io_ptr(png));
  if (length > c->out_capacity - c->out_size) {
    c->out_full = true;
    png_error(png, "output buffer full");
  }
  std::memcpy(c->out + c->out_size, data, length);
  c->out_size += length;
}

void on_flush(png_structp) {}

[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  Context* c = static_cast<Context*>(png_get_error_ptr(png));
  if (c->error[0] == '\0') std::snprintf(c->error, sizeof c->error, "%s", message ? message : "libpng error");
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}  // nothing a valid RGB image can trigger matters

// The libpng sequence. Kept free of C++ objects with destructors: libpng
// reports errors by longjmp back to the setjmp here.
int write_png(Context* c, const std::uint8_t* const* rows, png_uint_32 width, png_uint_32 height, int level) {
  png_structp png = png_create_write_struct_2(PNG_LIBPNG_VER_STRING, c, on_error, on_warning, c, on_malloc, on_free);
  if (png == nullptr) return 1;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    return 1;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return 1;
  }
  png_set_write_fn(png, c, on_write, on_flush);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, level);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, level <= 3 ? PNG_FILTER_SUB : PNG_ALL_FILTERS);
  png_write_info(png, info);
  png_set_filler(png, 0, PNG_FILLER_AFTER);  // rows are RGBA: drop the 4th byte
  png_write_image(png, const_cast<png_bytepp>(rows));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return 0;
}

}  // namespace

std::size_t PngEncoder::worst_case_bytes(int width_px, int height_px) {
  const std::size_t raw = static_cast<std::size_t>(height_px) * (static_cast<std::size_t>(width_px) * 3 + 1);
  // stored deflate blocks (5 bytes per 16 KiB), 12 bytes per 8 KiB IDAT chunk, headers
  return raw + (raw / 16383 + 1) * 5 + (raw / 8192 + 1) * 12 + 1024;
}

Result<std::unique_ptr<PngEncoder>> PngEncoder::create(int max_width_px, int max_height_px, int compression_level) {
  if (max_width_px < 1 || max_height_px < 1 || max_width_px > 16384 || max_height_px > 16384) {
    return invalid_argument("PNG size " + std::to_string(max_width_px) + " x " + std::to_string(max_height_px) +
                            " is outside 1..16384 pixels a side");
  }
  if (compression_level < 0 || compression_level > 9) {
    return invalid_argument("PNG compression level " + std::to_string(compression_level) + " is outside 0..9");
  }
  std::unique_ptr<PngEncoder> e(new PngEncoder());
  e->max_width_ = max_width_px;
  e->max_height_ = max_height_px;
  e->level_ = compression_level;
  // filter buffers: up to six rows of 4 bytes a pixel plus the filter byte
  e->arena_size_ = kArenaFixedBytes + 6 * (static_cast<std::size_t>(max_width_px) * 4 + 1 + kArenaAlign);
  e->arena_.reset(new std::uint8_t[e->arena_size_]);
  e->rows_.reset(new const std::uint8_t*[static_cast<std::size_t>(max_height_px)]);
  e->context_.reset(new Context());
  return e;
}

PngEncoder::~PngEncoder() = default;

Result<std::size_t> PngEncoder::encode(const std::uint8_t* rgba, int width_px, int height_px, std::size_t stride_bytes,
                                       std::uint8_t* out, std::size_t capacity_bytes) {
  if (rgba == nullptr || out == nullptr) return invalid_argument("PNG encode: null pixels or output buffer");
  if (width_px < 1 || height_px < 1 || width_px > max_width_ || height_px > max_height_) {
    return invalid_argument("PNG encode: image " + std::to_string(width_px) + " x " + std::to_string(height_px) +
                            " is outside the encoder's 1.." + std::to_string(max_width_) + " x 1.." +
                            std::to_string(max_height_));
  }
  if (stride_bytes < static_cast<std::size_t>(width_px) * 4) {
    return invalid_argument("PNG encode: row stride " + std::to_string(stride_bytes) + " bytes is under 4 x width");
  }
  for (int y = 0; y < height_px; ++y)
    rows_[static_cast<std::size_t>(y)] = rgba + static_cast<std::size_t>(y) * stride_bytes;
  Context& c = *context_;
  c = Context{};
  c.arena = arena_.get();
  c.arena_size = arena_size_;
  c.out = out;
  c.out_capacity = capacity_bytes;
  const int rc =
      write_png(&c, rows_.get(), static_cast<png_uint_32>(width_px), static_cast<png_uint_32>(height_px), level_);
  arena_high_water_ = c.arena_offset;
  if (rc != 0) {
    if (c.out_full) {
      return resource_error("PNG of " + std::to_string(width_px) + " x " + std::to_string(height_px) + " at level " +
                            std::to_string(level_) + " does not fit the " + std::to_string(capacity_bytes) +
                            "-byte output buffer");
    }
    if (c.arena_exhausted) {
      return resource_error("PNG encode: libpng needed more than the " + std::to_string(arena_size_) + "-byte arena");
    }
    return Status(Errc::io, std::string("PNG encode: libpng: ") + (c.error[0] ? c.error : "out of memory"));
  }
  return c.out_size;
}

}  // namespace visvol::render
