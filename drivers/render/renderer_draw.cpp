// The renderer's per-frame drawing: render() checks the frame, builds the
// path and overlay on the CPU (camera, slice profile, markers, bars) and
// draws the terrain, path, volume or slice and overlay, then reads it back.
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "drivers/render/overlay.hpp"
#include "drivers/render/renderer.hpp"
#include "drivers/render/renderer_impl.hpp"
#include "drivers/render/scene.hpp"

namespace visvol::render {

using detail::Box;
using detail::gl_bytes;
using detail::gl_count;
using detail::gl_offset;
using detail::gl_status;
using detail::OverlayBuilder;
using detail::Rgba;
using detail::Vec3;

namespace {

// Terrain mesh density: a vertex per 2 x 2 pixels; 3 x 3 in the volume view,
// whose plain terrain lies under the F_p fog (llvmpipe's vertex work is
// single-threaded and dominates large frames: a third less there).
constexpr double kPixelsPerVertex = 2.0;
constexpr double kVolumePixelsPerVertex = 3.0;
// Scenes larger than this many pixels ray-march at half resolution (a
// quarter of the cost; the fog is smooth) and are upsampled bilinearly.
constexpr long kFullResolutionVolumePixels = 320L * 320L;

constexpr Rgba kDark{0.06f, 0.06f, 0.07f, 1.0f};
constexpr Rgba kWhite{0.97f, 0.97f, 0.97f, 1.0f};
constexpr Rgba kStartColour{0.10f, 0.78f, 0.22f, 1.0f};
constexpr Rgba kHiddenFromColour{0.02f, 0.02f, 0.02f, 1.0f};
constexpr Rgba kVisibleToColour{0.92f, 0.16f, 0.86f, 1.0f};
constexpr Rgba kStalkColour{0.05f, 0.05f, 0.05f, 0.85f};
const float kLight[3] = {-0.5f, 0.5f, 0.70710678f};  // from the north-west, 45 degrees up
const float kPlainTerrain[3] = {0.56f, 0.55f, 0.52f};
const float kSliceGround[3] = {0.45f, 0.38f, 0.31f};

// Matrices to GL (column-major floats).
void set_matrix(GLint location, const detail::Mat4& m) {
  float f[16];
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) f[c * 4 + r] = static_cast<float>(m(r, c));
  }
  glUniformMatrix4fv(location, 1, GL_FALSE, f);
}

bool finite3(double a, double b, double c) { return std::isfinite(a) && std::isfinite(b) && std::isfinite(c); }

}  // namespace

double Renderer::Impl::ground_m(double x_m, double y_m) const {
  const double gi = std::clamp((x_m - origin_x_m) / spacing_m, 0.0, static_cast<double>(nx - 1));
  const double gj = std::clamp((origin_y_m - y_m) / spacing_m, 0.0, static_cast<double>(ny - 1));
  const int i = std::min(static_cast<int>(gi), nx - 2), j = std::min(static_cast<int>(gj), ny - 2);
  const double fi = gi - i, fj = gj - j;
  const auto h = [&](int a, int b) {
    return static_cast<double>(
        heights_m[static_cast<std::size_t>(b) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(a)]);
  };
  const double top = h(i, j) + fi * (h(i + 1, j) - h(i, j));
  const double bottom = h(i, j + 1) + fi * (h(i + 1, j + 1) - h(i, j + 1));
  return top + fj * (bottom - top);
}

namespace {

Status validate_path(const Frame& f, const RendererConfig& c) {
  if (f.path_size == 1 || f.path_size > c.max_path_vertices || (f.path_size > 0 && f.path == nullptr)) {
    return invalid_argument("path of " + std::to_string(f.path_size) + " vertices: need 0 or 2.." +
                            std::to_string(c.max_path_vertices));
  }
  for (std::size_t i = 0; i < f.path_size; ++i) {
    const PathPoint& p = f.path[i];
    if (!finite3(p.x_m, p.y_m, p.z_m)) {
      return invalid_argument("path vertex " + std::to_string(i) + ": position is not finite");
    }
    if (!(p.fp >= 0.0 && p.fp <= 1.0)) {
      return invalid_argument("path vertex " + std::to_string(i) + ": F_p " + std::to_string(p.fp) +
                              " is outside [0, 1]");
    }
  }
  if (f.view != View::slice) return Status::ok_status();
  if (f.path_size < 2) return invalid_argument("the slice view needs a path");
  double length_m = 0;
  for (std::size_t i = 1; i < f.path_size; ++i) {
    length_m += std::hypot(f.path[i].x_m - f.path[i - 1].x_m, f.path[i].y_m - f.path[i - 1].y_m);
  }
  if (!(length_m > 1e-6)) return invalid_argument("the slice view needs a path that moves horizontally");
  return Status::ok_status();
}

Status validate_markers(const Frame& f, const RendererConfig& c) {
  if (f.marker_count > c.max_markers || (f.marker_count > 0 && f.markers == nullptr)) {
    return invalid_argument(std::to_string(f.marker_count) + " markers: at most " + std::to_string(c.max_markers));
  }
  for (std::size_t i = 0; i < f.marker_count; ++i) {
    const Marker& mk = f.markers[i];
    if (!finite3(mk.x_m, mk.y_m, mk.z_m)) {
      return invalid_argument("marker " + std::to_string(i) + ": position is not finite");
    }
    if (mk.kind != MarkerKind::hidden_from && mk.kind != MarkerKind::visible_to) {
      return invalid_argument("marker " + std::to_string(i) + ": unknown kind");
    }
  }
  return Status::ok_status();
}

// Everything render() reads from a frame; messages name the bad field. Builds
// a message (allocates) only on failure.
Status validate_frame(const Frame& f, const RendererConfig& c) {
  if (f.width_px < kMinSidePx || f.height_px < kMinSidePx || f.width_px > c.max_width_px ||
      f.height_px > c.max_height_px) {
    return invalid_argument("frame size " + std::to_string(f.width_px) + " x " + std::to_string(f.height_px) +
                            " is outside " + std::to_string(kMinSidePx) + ".." + std::to_string(c.max_width_px) +
                            " x " + std::to_string(kMinSidePx) + ".." + std::to_string(c.max_height_px));
  }
  if (f.view != View::top && f.view != View::oblique && f.view != View::volume && f.view != View::slice) {
    return invalid_argument("unknown view");
  }
  VISVOL_RETURN_IF_ERROR(validate_path(f, c));
  VISVOL_RETURN_IF_ERROR(validate_markers(f, c));
  if (f.height_above_ground_m && !(std::isfinite(*f.height_above_ground_m) && *f.height_above_ground_m >= 0)) {
    return invalid_argument("height above ground " + std::to_string(*f.height_above_ground_m) +
                            " m is not a finite non-negative number");
  }
  return Status::ok_status();
}

// A marker: a rim in `rim`, filled in `fill`; shape by kind.
enum class Shape { disc, square, diamond };
void marker(OverlayBuilder& o, const PixelPoint& p, double radius, Shape shape, Rgba fill, Rgba rim) {
  const double r = radius, rr = radius + std::max(1.5, radius * 0.3);
  switch (shape) {
    case Shape::disc:
      o.disc(p.x, p.y, rr, rim);
      o.disc(p.x, p.y, r, fill);
      break;
    case Shape::square:
      o.rect(p.x - rr * 0.85, p.y - rr * 0.85, rr * 1.7, rr * 1.7, rim);
      o.rect(p.x - r * 0.85, p.y - r * 0.85, r * 1.7, r * 1.7, fill);
      break;
    case Shape::diamond:
      o.diamond(p.x, p.y, rr * 1.15, rim);
      o.diamond(p.x, p.y, r * 1.15, fill);
      break;
  }
}

void colour_bar(OverlayBuilder& o, const FrameLayout& l, int text_scale, double fp_max) {
  const PixelRect& b = l.colour_bar;
  const double edge = std::max(1, text_scale);
  o.rect(b.x - edge, b.y - edge, b.width + 2 * edge, b.height + 2 * edge, kDark);
  o.colour_ramp(b.x, b.y, b.width, b.height, 0.0, 1.0);
  const double gap = 2.0 * text_scale, glyph_h = detail::kGlyphHeight * text_scale;
  const auto label = [&](const char* s, double y) {
    o.text(b.x - edge - gap - OverlayBuilder::text_width(s, text_scale), y, s, text_scale, kWhite);
  };
  char top[16];
  std::snprintf(top, sizeof top, "%.2g", fp_max);
  label(top, b.y);
  label("0", b.y + b.height - glyph_h);
  const char* title = "Fp";
  o.text(b.x + b.width / 2.0 - OverlayBuilder::text_width(title, text_scale) / 2, b.y - edge - gap - glyph_h, title,
         text_scale, kWhite);
}

void scale_bar(OverlayBuilder& o, const PixelRect& scene, int margin, int text_scale, double metres_per_px,
               double& length_m) {
  length_m = detail::nice_length_m(0.3 * scene.width * metres_per_px);
  if (!(length_m > 0)) return;
  const double px = length_m / metres_per_px;
  const double bar_h = std::max(3, 2 * text_scale + 1), edge = std::max(1, text_scale);
  const double x = scene.x + margin, y = scene.y + scene.height - margin - bar_h;
  // white and grey halves in a dark frame: readable on the background and on terrain
  o.rect(x - edge, y - edge, px + 2 * edge, bar_h + 2 * edge, kDark);
  o.rect(x, y, px / 2, bar_h, kWhite);
  o.rect(x + px / 2, y, px / 2, bar_h, Rgba{0.5f, 0.5f, 0.5f, 1.0f});
  char label[32];
  detail::length_label(length_m, label, sizeof label);
  o.text(x, y - edge - 2 * text_scale - detail::kGlyphHeight * text_scale, label, text_scale, kWhite);
}

void north_arrow(OverlayBuilder& o, const PixelRect& scene, int margin, int text_scale, double dx, double dy) {
  const double length = std::max(14.0, 0.09 * std::min(scene.width, scene.height));
  const double glyph_h = detail::kGlyphHeight * text_scale;
  const double cx = scene.x + margin + length * 0.5, cy = scene.y + margin + glyph_h + 3 * text_scale + length * 0.5;
  const double px = -dy, py = dx;  // perpendicular
  const double tip_x = cx + dx * length / 2, tip_y = cy + dy * length / 2;
  const double notch_x = cx - dx * length * 0.25, notch_y = cy - dy * length * 0.25;
  const double base_x = cx - dx * length / 2, base_y = cy - dy * length / 2;
  const double w = length * 0.3;
  const Rgba shadow{0, 0, 0, 0.6f};
  for (int pass = 0; pass < 2; ++pass) {
    const double s = pass == 0 ? 1.0 : 0.0;  // the shadow, offset one pixel
    o.triangle(tip_x + s, tip_y + s, notch_x + s, notch_y + s, base_x + px * w + s, base_y + py * w + s,
               pass == 0 ? shadow : kWhite);
    o.triangle(tip_x + s, tip_y + s, notch_x + s, notch_y + s, base_x - px * w + s, base_y - py * w + s,
               pass == 0 ? shadow : kDark);
  }
  const char* n = "N";
  const double lx = tip_x + dx * (glyph_h * 0.5 + 2 * text_scale), ly = tip_y + dy * (glyph_h * 0.5 + 2 * text_scale);
  o.text(lx - OverlayBuilder::text_width(n, text_scale) / 2, ly - glyph_h / 2, n, text_scale, kWhite);
}

}  // namespace

void Renderer::Impl::path_to_scene(const Frame& f) {
  const std::size_t n = f.path_size;
  mean_path_z_m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    centres[i] = frame.to_scene(f.path[i].x_m, f.path[i].y_m, f.path[i].z_m);
    fps[i] = static_cast<float>(std::min(f.path[i].fp / fp_max, 1.0));
    mean_path_z_m += f.path[i].z_m / static_cast<double>(n);
  }
}

void Renderer::Impl::place_camera(const Frame& f, FrameLayout& layout) {
  // the terrain (top) or the field's block, widened to whatever of the path
  // and markers lies outside it
  Box box = f.view == View::top ? terrain_box : field_box;
  const auto widen = [&box](const Vec3& p) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  };
  for (std::size_t i = 0; i < f.path_size; ++i) widen(centres[i]);
  for (std::size_t i = 0; i < f.marker_count; ++i) {
    widen(frame.to_scene(f.markers[i].x_m, f.markers[i].y_m, f.markers[i].z_m));
  }
  camera = f.view == View::top ? detail::top_camera(box, layout.scene) : detail::oblique_camera(box, layout.scene);
  // metres per pixel and north on screen, at the terrain's centre
  const Vec3 centre((terrain_box.min + terrain_box.max) / 2);
  const std::optional<PixelPoint> c = camera.project(centre);
  const std::optional<PixelPoint> e = camera.project(centre + Vec3(100, 0, 0));
  const std::optional<PixelPoint> n = camera.project(centre + Vec3(0, 100, 0));
  const double east_px = (c && e) ? std::hypot(e->x - c->x, e->y - c->y) : 1.0;
  layout.metres_per_px = 100.0 / std::max(east_px, 1e-9);
  // a post's footprint on screen: the area spanned by 100 m east and north
  const double area_px2 = (c && e && n) ? std::fabs((e->x - c->x) * (n->y - c->y) - (e->y - c->y) * (n->x - c->x)) : 0;
  px_per_post = area_px2 > 0 ? std::sqrt(area_px2) * spacing_m / 100.0 : spacing_m / layout.metres_per_px;
  north_dx = 0;
  north_dy = -1;
  if (c && n && std::hypot(n->x - c->x, n->y - c->y) > 1e-9) {
    const double len = std::hypot(n->x - c->x, n->y - c->y);
    north_dx = (n->x - c->x) / len;
    north_dy = (n->y - c->y) / len;
  }
}

void Renderer::Impl::overlay_3d(const Frame& f, const Sizes& z, OverlayBuilder& o) const {
  // a stalk from the ground up to each marker where the view is at an angle
  const auto stalk_and_marker = [&](double x, double y, double h, Shape shape, Rgba fill, Rgba rim) {
    const std::optional<PixelPoint> at = camera.project(frame.to_scene(x, y, h));
    if (!at) return;
    if (f.view != View::top) {
      const std::optional<PixelPoint> foot = camera.project(frame.to_scene(x, y, ground_m(x, y)));
      if (foot) o.line(foot->x, foot->y, at->x, at->y, std::max(1.5, z.tube_radius_px * 0.6), kStalkColour);
    }
    marker(o, *at, z.marker_radius_px, shape, fill, rim);
  };
  for (std::size_t i = 0; i < f.marker_count; ++i) {
    const Marker& mk = f.markers[i];
    const bool hidden = mk.kind == MarkerKind::hidden_from;
    stalk_and_marker(mk.x_m, mk.y_m, mk.z_m, Shape::diamond, hidden ? kHiddenFromColour : kVisibleToColour,
                     hidden ? kWhite : kDark);
  }
  const std::size_t n = f.path_size;
  if (n >= 2) {
    stalk_and_marker(f.path[0].x_m, f.path[0].y_m, f.path[0].z_m, Shape::disc, kStartColour, kDark);
    stalk_and_marker(f.path[n - 1].x_m, f.path[n - 1].y_m, f.path[n - 1].z_m, Shape::square, kWhite, kDark);
  }
}

void Renderer::Impl::slice_profile(const Frame& f, FrameLayout& layout) {
  // distance along the path's ground track across, height up; one profile
  // texel (scene x, y, ground) per column
  const std::size_t n = f.path_size;
  arc_m[0] = 0;
  for (std::size_t i = 1; i < n; ++i) {
    arc_m[i] = arc_m[i - 1] + std::hypot(f.path[i].x_m - f.path[i - 1].x_m, f.path[i].y_m - f.path[i - 1].y_m);
  }
  const double total = arc_m[n - 1];  // > 0 (validate_frame)
  double lo = 1e300, hi = top_m;
  std::size_t seg = 0;
  const auto columns = static_cast<std::size_t>(layout.scene.width);
  for (std::size_t c = 0; c < columns; ++c) {
    const double s = (static_cast<double>(c) + 0.5) / static_cast<double>(columns) * total;
    while (seg + 2 < n && arc_m[seg + 1] < s) ++seg;
    const double len = arc_m[seg + 1] - arc_m[seg];
    const double t = len > 0 ? std::clamp((s - arc_m[seg]) / len, 0.0, 1.0) : 0.0;
    const double x = f.path[seg].x_m + t * (f.path[seg + 1].x_m - f.path[seg].x_m);
    const double y = f.path[seg].y_m + t * (f.path[seg + 1].y_m - f.path[seg].y_m);
    const double ground = ground_m(x, y);
    lo = std::min(lo, ground);
    const Vec3 p = frame.to_scene(x, y, ground);
    profile[c * 4 + 0] = static_cast<float>(p.x());
    profile[c * 4 + 1] = static_cast<float>(p.y());
    profile[c * 4 + 2] = static_cast<float>(p.z());
    profile[c * 4 + 3] = 0.0f;
  }
  for (std::size_t i = 0; i < n; ++i) {
    lo = std::min(lo, f.path[i].z_m);
    hi = std::max(hi, f.path[i].z_m);
  }
  const double span = std::max(hi - lo, 1.0);
  slice_length_m = total;
  slice_z_bottom_m = lo - 0.05 * span;
  slice_z_top_m = hi + 0.02 * span;
  layout.metres_per_px = total / layout.scene.width;
}

std::optional<PixelPoint> Renderer::Impl::slice_point(const PixelRect& scene, double distance_m, double z_m) const {
  if (!(slice_length_m > 0)) return std::nullopt;
  return PixelPoint{scene.x + distance_m / slice_length_m * scene.width,
                    scene.y + (slice_z_top_m - z_m) / (slice_z_top_m - slice_z_bottom_m) * scene.height};
}

void Renderer::Impl::overlay_slice(const Frame& f, const FrameLayout& layout, const Sizes& z, OverlayBuilder& o) const {
  // the path: a dark outline, then the line coloured by F_p, then the ends
  const PixelRect& scene = layout.scene;
  const std::size_t n = f.path_size;
  const double line_px = 2 * z.tube_radius_px;
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const PixelPoint a = *slice_point(scene, arc_m[i], f.path[i].z_m);
      const PixelPoint b = *slice_point(scene, arc_m[i + 1], f.path[i + 1].z_m);
      if (pass == 0) {
        o.line(a.x, a.y, b.x, b.y, line_px + 2 * z.outline_px, kDark);
      } else {
        o.line(a.x, a.y, b.x, b.y, line_px, kDark, fps[i], fps[i + 1]);
      }
    }
  }
  marker(o, *slice_point(scene, 0, f.path[0].z_m), z.marker_radius_px, Shape::disc, kStartColour, kDark);
  marker(o, *slice_point(scene, slice_length_m, f.path[n - 1].z_m), z.marker_radius_px, Shape::square, kWhite, kDark);
  // the heights of the panel's top and bottom edges
  char label[32];
  std::snprintf(label, sizeof label, "%.0f m", slice_z_top_m);
  o.text(scene.x + z.margin_px, scene.y + z.margin_px, label, z.text_scale, kWhite);
  std::snprintf(label, sizeof label, "%.0f m", slice_z_bottom_m);
  o.text(scene.x + scene.width - z.margin_px - OverlayBuilder::text_width(label, z.text_scale),
         scene.y + scene.height - z.margin_px - detail::kGlyphHeight * z.text_scale, label, z.text_scale, kWhite);
}

void Renderer::Impl::draw_terrain(const Frame& f, const PixelRect& scene, int mesh_step) const {
  const Mesh* mesh = &meshes.front();
  for (const Mesh& candidate : meshes) {
    if (candidate.step == mesh_step) mesh = &candidate;
  }
  glViewport(scene.x, scene.y, scene.width, scene.height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_BLEND);
  glUseProgram(terrain.id);
  set_matrix(terrain.view_proj, camera.view_proj);
  glUniform1i(terrain.field, 0);
  glUniform1i(terrain.colour_map, 1);
  glUniform3fv(terrain.tex_scale, 1, tex_scale);
  glUniform3fv(terrain.tex_offset, 1, tex_offset);
  glUniform3fv(terrain.light, 1, kLight);
  glUniform3fv(terrain.plain_colour, 1, kPlainTerrain);
  glUniform3fv(terrain.skirt_colour, 1, kSliceGround);
  if (f.view == View::volume) {
    glUniform1i(terrain.mode, 2);  // plain: the volume carries F_p
  } else if (f.height_above_ground_m || f.path_size == 0) {
    glUniform1i(terrain.mode, 1);
    const double hag = f.height_above_ground_m ? *f.height_above_ground_m : kDefaultHeightAboveGroundM;
    glUniform1f(terrain.height, static_cast<float>(hag * frame.exaggeration));
  } else {
    glUniform1i(terrain.mode, 0);
    glUniform1f(terrain.height, static_cast<float>((mean_path_z_m - frame.z_ref_m) * frame.exaggeration));
  }
  glBindVertexArray(mesh->vao);
  glDrawElements(GL_TRIANGLES, mesh->index_count, GL_UNSIGNED_INT, gl_offset(0));
}

void Renderer::Impl::draw_path(std::size_t count, const Sizes& z, double metres_per_px) const {
  // the outline (the tube inflated, depth not written), then the tube
  glBindVertexArray(tube_vao);
  glBindBuffer(GL_ARRAY_BUFFER, tube_vbo);
  glBufferSubData(GL_ARRAY_BUFFER, 0, gl_bytes(count * detail::kTubeSides * detail::kTubeFloats * sizeof(float)),
                  tube_data.data());
  glUseProgram(tube.id);
  set_matrix(tube.view_proj, camera.view_proj);
  glUniform1i(tube.colour_map, 1);
  glUniform3fv(tube.light, 1, kLight);
  glUniform3f(tube.outline_colour, kDark.r, kDark.g, kDark.b);
  const GLsizei indices = gl_count((count - 1) * detail::kTubeSides * 6);
  glDepthMask(GL_FALSE);
  glUniform1i(tube.outline, 1);
  glUniform1f(tube.inflate, static_cast<float>(z.outline_px * metres_per_px));
  glDrawElements(GL_TRIANGLES, indices, GL_UNSIGNED_INT, gl_offset(0));
  glDepthMask(GL_TRUE);
  glUniform1i(tube.outline, 0);
  glUniform1f(tube.inflate, 0.0f);
  glDrawElements(GL_TRIANGLES, indices, GL_UNSIGNED_INT, gl_offset(0));
}

void Renderer::Impl::draw_volume(const PixelRect& scene, int frame_w, int frame_h) const {
  // copy the opaque scene's depth, so the rays stop at the terrain and path
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, depth_fbo);
  glBlitFramebuffer(0, 0, frame_w, frame_h, 0, 0, frame_w, frame_h, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  // large scenes march at half resolution into their own buffer
  const bool half = static_cast<long>(scene.width) * scene.height > kFullResolutionVolumePixels;
  if (half) {
    glBindFramebuffer(GL_FRAMEBUFFER, half_fbo);
    glViewport(0, 0, (scene.width + 1) / 2, (scene.height + 1) / 2);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_BLEND);
  } else {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  }
  march_volume(scene, half);
  if (half) composite_half(scene);
}

void Renderer::Impl::march_volume(const PixelRect& scene, bool half) const {
  glDisable(GL_DEPTH_TEST);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, depth_tex);
  glUseProgram(volume.id);
  set_matrix(volume.inverse, camera.inverse);
  // the viewport the rays are cast through, and where its pixels' depths are
  const float scale = half ? 2.0f : 1.0f;
  const float vx = half ? 0.0f : static_cast<float>(scene.x), vy = half ? 0.0f : static_cast<float>(scene.y);
  glUniform4f(volume.viewport, vx, vy, static_cast<float>(scene.width) / scale,
              static_cast<float>(scene.height) / scale);
  if (half) {
    glUniform3f(volume.depth_map, static_cast<float>(scene.x), static_cast<float>(scene.y), 2.0f);
  } else {
    glUniform3f(volume.depth_map, 0.0f, 0.0f, 1.0f);
  }
  glUniform3f(volume.box_min, static_cast<float>(field_box.min.x()), static_cast<float>(field_box.min.y()),
              static_cast<float>(field_box.min.z()));
  glUniform3f(volume.box_max, static_cast<float>(field_box.max.x()), static_cast<float>(field_box.max.y()),
              static_cast<float>(field_box.max.z()));
  glUniform1i(volume.depth, 2);
  glUniform1i(volume.field, 0);
  glUniform1i(volume.colour_map, 1);
  glUniform3fv(volume.tex_scale, 1, tex_scale);
  glUniform3fv(volume.tex_offset, 1, tex_offset);
  glUniform1f(volume.step, volume_step);
  glUniform1i(volume.max_steps, volume_max_steps);
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void Renderer::Impl::composite_half(const PixelRect& scene) const {
  // blend the half-resolution volume over the frame (premultiplied)
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(scene.x, scene.y, scene.width, scene.height);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, half_tex);
  glUseProgram(composite.id);
  glUniform4f(composite.viewport, static_cast<float>(scene.x), static_cast<float>(scene.y),
              static_cast<float>(scene.width), static_cast<float>(scene.height));
  glUniform2f(composite.texture_size, static_cast<float>(half_width), static_cast<float>(half_height));
  glUniform1i(composite.half, 3);
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void Renderer::Impl::draw_slice(const PixelRect& scene) const {
  glViewport(scene.x, scene.y, scene.width, scene.height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, profile_tex);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, scene.width, 1, GL_RGBA, GL_FLOAT, profile.data());
  glUseProgram(slice.id);
  glUniform4f(slice.viewport, static_cast<float>(scene.x), static_cast<float>(scene.y), static_cast<float>(scene.width),
              static_cast<float>(scene.height));
  glUniform1i(slice.profile, 2);
  glUniform1i(slice.field, 0);
  glUniform1i(slice.colour_map, 1);
  glUniform3fv(slice.tex_scale, 1, tex_scale);
  glUniform3fv(slice.tex_offset, 1, tex_offset);
  glUniform1f(slice.z_top, static_cast<float>((slice_z_top_m - frame.z_ref_m) * frame.exaggeration));
  glUniform1f(slice.z_bottom, static_cast<float>((slice_z_bottom_m - frame.z_ref_m) * frame.exaggeration));
  glUniform3fv(slice.ground_colour, 1, kSliceGround);
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void Renderer::Impl::draw_overlay(const OverlayBuilder& o, int frame_w, int frame_h) const {
  glViewport(0, 0, frame_w, frame_h);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(overlay.id);
  glUniform2f(overlay.size, static_cast<float>(frame_w), static_cast<float>(frame_h));
  glUniform1i(overlay.colour_map, 1);
  glBindVertexArray(overlay_vao);
  glBindBuffer(GL_ARRAY_BUFFER, overlay_vbo);
  glBufferSubData(GL_ARRAY_BUFFER, 0, gl_bytes(o.vertex_count() * detail::kOverlayFloats * sizeof(float)),
                  overlay_data.data());
  glDrawArrays(GL_TRIANGLES, 0, gl_count(o.vertex_count()));
  glBindVertexArray(0);
}

namespace {

// Marks scale with the frame's smaller side, with floors for thumbnails.
Sizes sizes_for(const Frame& f, const detail::BaseLayout& base) {
  const double short_side = std::min(f.width_px, f.height_px);
  Sizes z;
  z.tube_radius_px = std::max(2.0, short_side / 170.0);
  z.outline_px = std::max(1.0, z.tube_radius_px * 0.4);
  z.marker_radius_px = std::max(4.0, short_side * 0.022);
  z.margin_px = base.margin_px;
  z.text_scale = base.text_scale;
  return z;
}

}  // namespace

void Renderer::Impl::prepare(const Frame& f, const Sizes& z, FrameLayout& layout, OverlayBuilder& o) {
  // geometry and overlay on the CPU, into the reserved arrays
  width = f.width_px;
  height = f.height_px;
  view = f.view;
  path_to_scene(f);
  if (f.view != View::slice) {
    place_camera(f, layout);
    if (f.path_size >= 2) {
      detail::tube_vertices(centres.data(), fps.data(), f.path_size, z.tube_radius_px * layout.metres_per_px,
                            tube_data.data());
    }
    overlay_3d(f, z, o);
    north_arrow(o, layout.scene, z.margin_px, z.text_scale, north_dx, north_dy);
  } else {
    slice_profile(f, layout);
    overlay_slice(f, layout, z, o);
  }
  scale_bar(o, layout.scene, z.margin_px, z.text_scale, layout.metres_per_px, layout.scale_bar_m);
  colour_bar(o, layout, z.text_scale, fp_max);
  layout.overlay_vertices_dropped = o.dropped();
}

void Renderer::Impl::draw(const Frame& f, const Sizes& z, const FrameLayout& layout, const OverlayBuilder& o,
                          const float (&background)[3], int mesh_step) const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, f.width_px, f.height_px);
  glClearColor(background[0], background[1], background[2], 1.0f);
  glClearDepth(1.0);
  // clear the frame's corner only: the buffers are the largest frame's size
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, f.width_px, f.height_px);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_3D, field_tex);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, colour_map_tex);
  if (f.view != View::slice) {
    draw_terrain(f, layout.scene, mesh_step);
    if (f.path_size >= 2) draw_path(f.path_size, z, layout.metres_per_px);
    if (f.view == View::volume) draw_volume(layout.scene, f.width_px, f.height_px);
  } else {
    draw_slice(layout.scene);
  }
  draw_overlay(o, f.width_px, f.height_px);
}

void Renderer::Impl::read_back(int w, int h) {
  // window rows run top to bottom (scene.hpp), so this is the image
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
}

Status Renderer::render(const Frame& f) {
  VISVOL_RETURN_IF_ERROR(validate_frame(f, config_));
  Impl& m = *impl_;
  VISVOL_RETURN_IF_ERROR(m.context->make_current());
  const detail::BaseLayout base = detail::base_layout(f.width_px, f.height_px);
  const Sizes sizes = sizes_for(f, base);
  layout_ = base.layout;
  OverlayBuilder o(m.overlay_data.data(), m.overlay_capacity);
  m.prepare(f, sizes, layout_, o);
  const int mesh_step = detail::choose_mesh_step(info_.mesh_steps, m.px_per_post,
                                                 f.view == View::volume ? kVolumePixelsPerVertex : kPixelsPerVertex);
  m.draw(f, sizes, layout_, o, config_.background_rgb, mesh_step);
  m.read_back(f.width_px, f.height_px);
  return gl_status("drawing the frame");
}

}  // namespace visvol::render
