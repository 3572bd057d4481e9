// Private to drivers/render: the renderer's state (Renderer::Impl) and the GL
// helpers its set-up (renderer_setup.cpp) and its drawing (renderer_draw.cpp)
// share. Nothing outside drivers/render includes it.
#pragma once

#include <GL/glcorearb.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "drivers/render/gl_context.hpp"
#include "drivers/render/overlay.hpp"
#include "drivers/render/png_encoder.hpp"
#include "drivers/render/renderer.hpp"
#include "drivers/render/scene.hpp"
#include "storage/cached_level.hpp"

namespace visvol::render {
namespace detail {

inline GLsizei gl_count(std::size_t n) { return static_cast<GLsizei>(n); }
inline GLsizeiptr gl_bytes(std::size_t n) { return static_cast<GLsizeiptr>(n); }
inline const void* gl_offset(std::size_t bytes) {
  // GL takes a buffer offset as a pointer: nothing is dereferenced
  return reinterpret_cast<const void*>(static_cast<std::uintptr_t>(bytes));  // NOLINT(performance-no-int-to-ptr)
}

inline Status gl_status(const char* where) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return Status::ok_status();
  char text[96];
  std::snprintf(text, sizeof text, "OpenGL error 0x%04x %s", e, where);
  return Status(Errc::io, text);
}

}  // namespace detail

// Pixel sizes of a frame's marks, from its smaller side.
struct Sizes {
  double tube_radius_px, outline_px, marker_radius_px;
  int margin_px, text_scale;
};

struct Renderer::Impl {
  struct Mesh {
    int step = 1, nx = 0, ny = 0;
    GLuint vao = 0, vbo = 0, ibo = 0;
    GLsizei index_count = 0;
  };
  struct TerrainProgram {
    GLuint id = 0;
    GLint view_proj, field, colour_map, tex_scale, tex_offset, mode, height, light, plain_colour, skirt_colour;
  };
  struct TubeProgram {
    GLuint id = 0;
    GLint view_proj, inflate, colour_map, light, outline, outline_colour;
  };
  struct OverlayProgram {
    GLuint id = 0;
    GLint size, colour_map;
  };
  struct VolumeProgram {
    GLuint id = 0;
    GLint inverse, viewport, depth_map, box_min, box_max, depth, field, colour_map, tex_scale, tex_offset, step,
        max_steps;
  };
  struct CompositeProgram {
    GLuint id = 0;
    GLint viewport, texture_size, half;
  };
  struct SliceProgram {
    GLuint id = 0;
    GLint viewport, profile, field, colour_map, tex_scale, tex_offset, z_top, z_bottom, ground_colour;
  };

  std::unique_ptr<GlContext> context;
  std::shared_ptr<const storage::Pack> pack;

  // terrain (level 0) and the scene
  int nx = 0, ny = 0;
  double spacing_m = 0, origin_x_m = 0, origin_y_m = 0, top_m = 0;
  std::vector<float> heights_m;
  detail::SceneFrame frame;
  detail::Box terrain_box, field_box;
  std::vector<Mesh> meshes;

  // F_p texture and how scene coordinates reach it
  GLuint field_tex = 0, colour_map_tex = 0, depth_tex = 0, profile_tex = 0;
  float tex_scale[3] = {1, 1, 1}, tex_offset[3] = {0, 0, 0};
  double fp_max = 1;  // F_p at the top of the colour scale
  float volume_step = 1;
  int volume_max_steps = 1;

  // framebuffers at the largest size
  GLuint fbo = 0, colour_rb = 0, depth_rb = 0, depth_fbo = 0;
  GLuint half_fbo = 0, half_tex = 0;  // the volume at half resolution
  int half_width = 0, half_height = 0;

  TerrainProgram terrain;
  TubeProgram tube;
  OverlayProgram overlay;
  VolumeProgram volume;
  CompositeProgram composite;
  SliceProgram slice;

  GLuint tube_vao = 0, tube_vbo = 0, tube_ibo = 0;
  GLuint overlay_vao = 0, overlay_vbo = 0;
  GLuint empty_vao = 0;

  // per-frame scratch, reserved at create()
  std::vector<detail::Vec3> centres;
  std::vector<float> fps;
  std::vector<double> arc_m;
  std::vector<float> tube_data;
  std::vector<float> overlay_data;
  std::size_t overlay_capacity = 0;
  std::vector<float> profile;
  std::vector<std::uint8_t> pixels;
  std::unique_ptr<PngEncoder> png;

  // the last frame
  int width = 0, height = 0;
  View view = View::oblique;
  detail::Camera camera;
  double north_dx = 0, north_dy = -1;  // north on screen, a unit vector in pixels
  double px_per_post = 1;              // a post spacing on screen at the terrain's centre (mesh choice)
  double mean_path_z_m = 0;
  double slice_length_m = 0, slice_z_top_m = 0, slice_z_bottom_m = 0;

  double ground_m(double x_m, double y_m) const;
  Status build_meshes(int max_width, int max_height);
  Status build_field_texture(const storage::CachedLevel& level, std::size_t max_voxels, double fp_max_config,
                             SceneInfo& info);
  Status build_programs();
  Status build_surface_programs();  // terrain, tube, overlay
  Status build_field_programs();    // volume, its composite, slice
  void upload_field(const std::vector<float>& mean, int tx, int ty, int tz);
  void map_field_texture(const fields::VolumeGeometry& g, int stride, int tx, int ty);
  void load_terrain(const storage::CachedLevel& level, double vertical_exaggeration);
  Status build_gl(const storage::CachedLevel& level, const RendererConfig& config, SceneInfo& info);
  Status build_buffers(const RendererConfig& config);
  Status build_frame_targets(int w, int h);
  Status build_half_target(int w, int h);
  void build_geometry_buffers(const RendererConfig& config);
  void reserve_scratch(const RendererConfig& config);
  void upload_colour_map(const TransferFunction& tf);

  // the stages of a frame (render())
  void prepare(const Frame& f, const Sizes& sizes, FrameLayout& layout, detail::OverlayBuilder& o);
  void draw(const Frame& f, const Sizes& sizes, const FrameLayout& layout, const detail::OverlayBuilder& o,
            const float (&background)[3], int mesh_step) const;
  void read_back(int w, int h);
  void path_to_scene(const Frame& f);
  void place_camera(const Frame& f, FrameLayout& layout);
  void overlay_3d(const Frame& f, const Sizes& sizes, detail::OverlayBuilder& o) const;
  void slice_profile(const Frame& f, FrameLayout& layout);
  void overlay_slice(const Frame& f, const FrameLayout& layout, const Sizes& sizes, detail::OverlayBuilder& o) const;
  void draw_terrain(const Frame& f, const PixelRect& scene, int mesh_step) const;
  void draw_path(std::size_t count, const Sizes& sizes, double metres_per_px) const;
  void draw_volume(const PixelRect& scene, int frame_w, int frame_h) const;
  void march_volume(const PixelRect& scene, bool half) const;
  void composite_half(const PixelRect& scene) const;
  void draw_slice(const PixelRect& scene) const;
  void draw_overlay(const detail::OverlayBuilder& o, int frame_w, int frame_h) const;
  std::optional<PixelPoint> slice_point(const PixelRect& scene, double distance_m, double z_m) const;
};

}  // namespace visvol::render
