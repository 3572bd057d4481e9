#include "drivers/render/overlay.hpp"

#include <cmath>

#include "base/angles.hpp"

namespace visvol::render::detail {

namespace {

constexpr int kDiscSegments = 20;

struct Glyph {
  char c;
  std::uint8_t rows[kGlyphHeight];
};

// 5 x 7 glyphs; bit 4 is the leftmost pixel of a row.
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}}, {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}}, {'N', {0x11, 0x19, 0x15, 0x13, 0x11, 0x11, 0x11}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}}, {'p', {0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10}},
};

constexpr Rgba kShadow{0.0f, 0.0f, 0.0f, 0.85f};

}  // namespace

const std::uint8_t* glyph_rows(char c) {
  for (const Glyph& g : kFont) {
    if (g.c == c) return g.rows;
  }
  return nullptr;
}

void OverlayBuilder::vertex(double x, double y, Rgba c, float fp) {
  if (count_ >= capacity_) {
    ++dropped_;
    return;
  }
  float* v = out_ + count_ * kOverlayFloats;
  v[0] = static_cast<float>(x);
  v[1] = static_cast<float>(y);
  v[2] = c.r;
  v[3] = c.g;
  v[4] = c.b;
  v[5] = c.a;
  v[6] = fp;
  ++count_;
}

void OverlayBuilder::triangle(double x0, double y0, double x1, double y1, double x2, double y2, Rgba c) {
  if (count_ + 3 > capacity_) {
    dropped_ += 3;
    return;
  }
  vertex(x0, y0, c, -1);
  vertex(x1, y1, c, -1);
  vertex(x2, y2, c, -1);
}

void OverlayBuilder::rect(double x, double y, double w, double h, Rgba c) {
  triangle(x, y, x + w, y, x, y + h, c);
  triangle(x + w, y, x + w, y + h, x, y + h, c);
}

void OverlayBuilder::colour_ramp(double x, double y, double w, double h, double fp_bottom, double fp_top) {
  if (count_ + 6 > capacity_) {
    dropped_ += 6;
    return;
  }
  const Rgba none{0, 0, 0, 1};
  const auto top = static_cast<float>(fp_top), bottom = static_cast<float>(fp_bottom);
  vertex(x, y, none, top);
  vertex(x + w, y, none, top);
  vertex(x, y + h, none, bottom);
  vertex(x + w, y, none, top);
  vertex(x + w, y + h, none, bottom);
  vertex(x, y + h, none, bottom);
}

void OverlayBuilder::line(double x0, double y0, double x1, double y1, double width, Rgba c, float fp0, float fp1) {
  const double dx = x1 - x0, dy = y1 - y0;
  const double length = std::hypot(dx, dy);
  if (length < 1e-9) return;
  if (count_ + 6 > capacity_) {
    dropped_ += 6;
    return;
  }
  const double nx = -dy / length * width / 2, ny = dx / length * width / 2;
  vertex(x0 + nx, y0 + ny, c, fp0);
  vertex(x1 + nx, y1 + ny, c, fp1);
  vertex(x0 - nx, y0 - ny, c, fp0);
  vertex(x1 + nx, y1 + ny, c, fp1);
  vertex(x1 - nx, y1 - ny, c, fp1);
  vertex(x0 - nx, y0 - ny, c, fp0);
}

void OverlayBuilder::disc(double cx, double cy, double radius, Rgba c) {
  for (int k = 0; k < kDiscSegments; ++k) {
    const double a0 = 2 * kPi * k / kDiscSegments, a1 = 2 * kPi * (k + 1) / kDiscSegments;
    triangle(cx, cy, cx + radius * std::cos(a0), cy + radius * std::sin(a0), cx + radius * std::cos(a1),
             cy + radius * std::sin(a1), c);
  }
}

void OverlayBuilder::diamond(double cx, double cy, double radius, Rgba c) {
  triangle(cx, cy - radius, cx + radius, cy, cx - radius, cy, c);
  triangle(cx - radius, cy, cx + radius, cy, cx, cy + radius, c);
}

double OverlayBuilder::text_width(const char* s, int scale) {
  int n = 0;
  for (const char* p = s; *p; ++p) ++n;
  return n > 0 ? (n * kGlyphAdvance - 1) * scale : 0;
}

void OverlayBuilder::glyphs(double x, double y, const char* s, int scale, Rgba c) {
  for (; *s; ++s, x += kGlyphAdvance * scale) {
    const std::uint8_t* rows = glyph_rows(*s);
    if (rows == nullptr) continue;
    for (int r = 0; r < kGlyphHeight; ++r) {
      // one rectangle per run of set pixels in the row
      int col = 0;
      while (col < kGlyphWidth) {
        if (!(rows[r] & (0x10 >> col))) {
          ++col;
          continue;
        }
        int end = col;
        while (end < kGlyphWidth && (rows[r] & (0x10 >> end))) ++end;
        rect(x + col * scale, y + r * scale, (end - col) * scale, scale, c);
        col = end;
      }
    }
  }
}

void OverlayBuilder::text(double x, double y, const char* s, int scale, Rgba c) {
  glyphs(x + scale, y + scale, s, scale, kShadow);
  glyphs(x, y, s, scale, c);
}

}  // namespace visvol::render::detail
