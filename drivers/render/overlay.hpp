// The picture's flat overlay (colour bar, labels, scale bar, north arrow,
// markers, the slice view's path) as triangles in pixel coordinates, written
// into a caller-reserved array: no allocation per frame.
//
// Vertex: x_px, y_px (y down), r, g, b, a, fp (7 floats). fp >= 0 takes the
// colour from the F_p colour map instead of r, g, b (the colour bar, the
// slice view's path).
//
// Text: a built-in 5 x 7 pixel font of the characters the picture needs
// (digits, '.', '-', ' ', 'k', 'm', 'N', 'F', 'p'); other characters are
// left blank. Not thread-safe (one builder per frame).
#pragma once

#include <cstddef>
#include <cstdint>

namespace visvol::render::detail {

inline constexpr int kOverlayFloats = 7;
inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;

struct Rgba {
  float r, g, b, a;
};

// The 7 rows of a glyph (bit 4 is the leftmost pixel), or nullptr.
const std::uint8_t* glyph_rows(char c);

class OverlayBuilder {
 public:
  // `out` holds capacity_vertices vertices.
  OverlayBuilder(float* out, std::size_t capacity_vertices) : out_(out), capacity_(capacity_vertices) {}

  void triangle(double x0, double y0, double x1, double y1, double x2, double y2, Rgba c);
  void rect(double x, double y, double w, double h, Rgba c);
  // A rectangle whose colour is the colour map, fp_bottom at its bottom edge
  // to fp_top at its top edge.
  void colour_ramp(double x, double y, double w, double h, double fp_bottom, double fp_top);
  // A segment `width` pixels wide; fp0/fp1 >= 0 colour it from the colour map.
  void line(double x0, double y0, double x1, double y1, double width, Rgba c, float fp0 = -1, float fp1 = -1);
  void disc(double cx, double cy, double radius, Rgba c);
  void diamond(double cx, double cy, double radius, Rgba c);
  // Text with its top-left corner at (x, y), `scale` pixels per font pixel,
  // with a one-pixel dark shadow so it reads on any background.
  void text(double x, double y, const char* s, int scale, Rgba c);
  static double text_width(const char* s, int scale);

  std::size_t vertex_count() const { return count_; }
  // Vertices that did not fit (the renderer reserves enough; a non-zero
  // count is a bug, reported by the tests).
  std::size_t dropped() const { return dropped_; }

 private:
  void vertex(double x, double y, Rgba c, float fp);
  void glyphs(double x, double y, const char* s, int scale, Rgba c);

  float* out_;
  std::size_t capacity_;
  std::size_t count_ = 0;
  std::size_t dropped_ = 0;
};

}  // namespace visvol::render::detail
