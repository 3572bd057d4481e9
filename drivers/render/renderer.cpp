#include "drivers/render/renderer.hpp"

#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "drivers/render/gl_context.hpp"
#include "drivers/render/overlay.hpp"
#include "drivers/render/png_encoder.hpp"
#include "drivers/render/scene.hpp"
#include "drivers/render/shaders.hpp"

namespace visvol::render {

using detail::Box;
using detail::Camera;
using detail::OverlayBuilder;
using detail::Rgba;
using detail::SceneFrame;
using detail::Vec3;

const char* to_string(View view) {
  switch (view) {
    case View::top: return "top";
    case View::oblique: return "oblique";
    case View::volume: return "volume";
    case View::slice: return "slice";
  }
  return "?";
}

Result<View> parse_view(const std::string& text) {
  for (View v : {View::top, View::oblique, View::volume, View::slice}) {
    if (text == to_string(v)) return v;
  }
  return invalid_argument("view '" + text + "' is not one of top, oblique, volume, slice");
}

namespace {

// Samples along the volume box's diagonal: the ray-marching step.
constexpr double kVolumeStepsPerDiagonal = 256;
constexpr int kColourMapTexels = 256;
// Terrain mesh density: a vertex per 2 x 2 pixels; 3 x 3 in the volume view,
// whose plain terrain lies under the F_p fog (llvmpipe's vertex work is
// single-threaded and dominates large frames: a third less there).
constexpr double kPixelsPerVertex = 2.0;
constexpr double kVolumePixelsPerVertex = 3.0;
constexpr int kWarmupSidePx = 64;
// Scenes larger than this many pixels ray-march at half resolution (a
// quarter of the cost; the fog is smooth) and are upsampled bilinearly.
constexpr long kFullResolutionVolumePixels = 320L * 320L;
// Overlay vertices beyond the path and markers: text, bars, arrow (measured
// under 4000 at 4096 x 4096; the tests check nothing is dropped).
constexpr std::size_t kOverlayBaseVertices = 16384;
constexpr std::size_t kOverlayVerticesPerPathPoint = 12;  // slice view: outline and line
constexpr std::size_t kOverlayVerticesPerMarker = 300;    // stalk, rim and fill

constexpr Rgba kDark{0.06f, 0.06f, 0.07f, 1.0f};
constexpr Rgba kWhite{0.97f, 0.97f, 0.97f, 1.0f};
constexpr Rgba kStartColour{0.10f, 0.78f, 0.22f, 1.0f};
constexpr Rgba kHiddenFromColour{0.02f, 0.02f, 0.02f, 1.0f};
constexpr Rgba kVisibleToColour{0.92f, 0.16f, 0.86f, 1.0f};
constexpr Rgba kStalkColour{0.05f, 0.05f, 0.05f, 0.85f};
const float kLight[3] = {-0.5f, 0.5f, 0.70710678f};  // from the north-west, 45 degrees up
const float kPlainTerrain[3] = {0.56f, 0.55f, 0.52f};
const float kSliceGround[3] = {0.45f, 0.38f, 0.31f};

GLsizei gl_count(std::size_t n) { return static_cast<GLsizei>(n); }
GLsizeiptr gl_bytes(std::size_t n) { return static_cast<GLsizeiptr>(n); }
const void* gl_offset(std::size_t bytes) { return reinterpret_cast<const void*>(static_cast<std::uintptr_t>(bytes)); }

// Vertex arrays whose attributes 0, 1, 2 are `sizes` floats each, interleaved.
void vertex_layout(const int (&sizes)[3]) {
  const GLsizei stride = static_cast<GLsizei>((sizes[0] + sizes[1] + sizes[2]) * static_cast<int>(sizeof(float)));
  std::size_t offset = 0;
  for (GLuint a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride, gl_offset(offset));
    offset += static_cast<std::size_t>(sizes[a]) * sizeof(float);
  }
}
static_assert(detail::kTerrainFloats == 3 + 3 + 1 && detail::kTubeFloats == 3 + 3 + 1 &&
                  detail::kOverlayFloats == 2 + 4 + 1,
              "vertex_layout's attribute sizes match the vertex formats");

Result<GLuint> compile(GLenum kind, const char* source, const char* name) {
  const GLuint s = glCreateShader(kind);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = GL_FALSE;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[1024] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    return Status(Errc::unsupported, std::string("shader ") + name + " does not compile: " + log);
  }
  return s;
}

Result<GLuint> link(const char* vertex, const char* fragment, const char* name) {
  Result<GLuint> vs = compile(GL_VERTEX_SHADER, vertex, name);
  if (!vs.ok()) return vs.status();
  Result<GLuint> fs = compile(GL_FRAGMENT_SHADER, fragment, name);
  if (!fs.ok()) {
    glDeleteShader(*vs);
    return fs.status();
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, *vs);
  glAttachShader(p, *fs);
  glLinkProgram(p);
  glDeleteShader(*vs);
  glDeleteShader(*fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[1024] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    return Status(Errc::unsupported, std::string("program ") + name + " does not link: " + log);
  }
  return p;
}

Status gl_status(const char* where) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return Status::ok_status();
  char text[96];
  std::snprintf(text, sizeof text, "OpenGL error 0x%04x %s", e, where);
  return Status(Errc::io, text);
}

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
  SceneFrame frame;
  Box terrain_box, field_box;
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
  std::vector<Vec3> centres;
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
  Camera camera;
  double north_dx = 0, north_dy = -1;  // north on screen, a unit vector in pixels
  double px_per_post = 1;              // a post spacing on screen at the terrain's centre (mesh choice)
  double mean_path_z_m = 0;
  double slice_length_m = 0, slice_z_top_m = 0, slice_z_bottom_m = 0;

  double ground_m(double x_m, double y_m) const;
  Status build_meshes(int max_width, int max_height);
  Status build_field_texture(const storage::PackLevel& level, std::size_t max_voxels, double fp_max_config,
                             SceneInfo& info);
  Status build_programs();
  Status build_surface_programs();  // terrain, tube, overlay
  Status build_field_programs();    // volume, its composite, slice
  void upload_field(const std::vector<float>& mean, int tx, int ty, int tz);
  void map_field_texture(const fields::VolumeGeometry& g, int stride, int tx, int ty);
  void load_terrain(const storage::PackLevel& level, double vertical_exaggeration);
  Status build_gl(const storage::PackLevel& level, const RendererConfig& config, SceneInfo& info);
  Status build_buffers(const RendererConfig& config);
  Status build_frame_targets(int w, int h);
  Status build_half_target(int w, int h);
  void build_geometry_buffers(const RendererConfig& config);
  void reserve_scratch(const RendererConfig& config);
  void upload_colour_map(const TransferFunction& tf);

  // the stages of a frame (render())
  void prepare(const Frame& f, const Sizes& sizes, FrameLayout& layout, OverlayBuilder& o);
  void draw(const Frame& f, const Sizes& sizes, const FrameLayout& layout, const OverlayBuilder& o,
            const float (&background)[3], int mesh_step) const;
  void read_back(int w, int h);
  void path_to_scene(const Frame& f);
  void place_camera(const Frame& f, FrameLayout& layout);
  void overlay_3d(const Frame& f, const Sizes& sizes, OverlayBuilder& o) const;
  void slice_profile(const Frame& f, FrameLayout& layout);
  void overlay_slice(const Frame& f, const FrameLayout& layout, const Sizes& sizes, OverlayBuilder& o) const;
  void draw_terrain(const Frame& f, const PixelRect& scene, int mesh_step) const;
  void draw_path(std::size_t count, const Sizes& sizes, double metres_per_px) const;
  void draw_volume(const PixelRect& scene, int frame_w, int frame_h) const;
  void march_volume(const PixelRect& scene, bool half) const;
  void composite_half(const PixelRect& scene) const;
  void draw_slice(const PixelRect& scene) const;
  void draw_overlay(const OverlayBuilder& o, int frame_w, int frame_h) const;
  std::optional<PixelPoint> slice_point(const PixelRect& scene, double distance_m, double z_m) const;
};

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

Status Renderer::Impl::build_meshes(int max_width, int max_height) {
  const int posts = std::max(nx, ny);
  const detail::BaseLayout largest = detail::base_layout(max_width, max_height);
  const int px = std::max(largest.layout.scene.width, largest.layout.scene.height);
  // the finest mesh has a vertex every two pixels at the largest size
  const int finest = std::max(1, static_cast<int>(std::floor(2.0 * posts / std::max(1, px))));
  for (int step : detail::mesh_steps(finest, posts)) {
    detail::TerrainMesh m =
        detail::terrain_mesh(heights_m, nx, ny, step, spacing_m, origin_x_m, origin_y_m, frame, field_box.min.z());
    Mesh g;
    g.step = step;
    g.nx = m.nx;
    g.ny = m.ny;
    g.index_count = gl_count(m.indices.size());
    glGenVertexArrays(1, &g.vao);
    glBindVertexArray(g.vao);
    glGenBuffers(1, &g.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
    glBufferData(GL_ARRAY_BUFFER, gl_bytes(m.vertices.size() * sizeof(float)), m.vertices.data(), GL_STATIC_DRAW);
    glGenBuffers(1, &g.ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, gl_bytes(m.indices.size() * sizeof(std::uint32_t)), m.indices.data(),
                 GL_STATIC_DRAW);
    vertex_layout({3, 3, 1});  // position, normal, skirt flag
    glBindVertexArray(0);
    meshes.push_back(g);
  }
  return gl_status("building the terrain meshes");
}

namespace {

int texels_of(int posts, int stride) { return (posts + stride - 1) / stride; }

// The smallest post stride whose F_p texture fits the voxel budget and the
// GL's 3D texture size.
int volume_stride(const fields::VolumeGeometry& g, std::size_t max_voxels, int max_3d) {
  int stride = 1;
  const auto voxels = [&](int s) {
    return static_cast<std::size_t>(texels_of(g.nx, s)) * static_cast<std::size_t>(texels_of(g.ny, s)) *
           static_cast<std::size_t>(g.nz);
  };
  while (voxels(stride) > max_voxels || texels_of(g.nx, stride) > max_3d || texels_of(g.ny, stride) > max_3d) {
    ++stride;
  }
  return stride;
}

// Level 0's F_p averaged over stride x stride posts, x fastest, then y
// (southward), then z; `largest` is the largest F_p of a single voxel. The
// coarser levels of the pack have a wider range (another field), so they are
// not used for this.
std::vector<float> averaged_field(const storage::PackLevel& level, int stride, double& largest) {
  const fields::VolumeGeometry& g = level.geometry();
  const int tx = texels_of(g.nx, stride), ty = texels_of(g.ny, stride);
  std::vector<float> mean(static_cast<std::size_t>(tx) * static_cast<std::size_t>(ty) * static_cast<std::size_t>(g.nz));
  largest = 0;
  std::size_t n = 0;
  for (int k = 0; k < g.nz; ++k) {
    for (int bj = 0; bj < ty; ++bj) {
      for (int bi = 0; bi < tx; ++bi) {
        double sum = 0;
        int count = 0;
        for (int j = bj * stride; j < std::min(g.ny, (bj + 1) * stride); ++j) {
          for (int i = bi * stride; i < std::min(g.nx, (bi + 1) * stride); ++i) {
            const double v = static_cast<double>(level.voxel(i, j, k));
            largest = std::max(largest, v);
            sum += v;
            ++count;
          }
        }
        mean[n++] = static_cast<float>(sum / count);
      }
    }
  }
  return mean;
}

}  // namespace

void Renderer::Impl::upload_field(const std::vector<float>& mean, int tx, int ty, int tz) {
  // stored as F_p / fp_max: the colour scale's full 8 bits
  std::vector<std::uint8_t> data(mean.size());
  for (std::size_t v = 0; v < mean.size(); ++v) {
    data[v] = static_cast<std::uint8_t>(std::lround(std::clamp(mean[v] / fp_max, 0.0, 1.0) * 255.0));
  }
  glGenTextures(1, &field_tex);
  glBindTexture(GL_TEXTURE_3D, field_tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R8, tx, ty, tz, 0, GL_RED, GL_UNSIGNED_BYTE, data.data());
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

void Renderer::Impl::map_field_texture(const fields::VolumeGeometry& g, int stride, int tx, int ty) {
  // texel (a, b, c) centres at world x0 + (a stride + (stride - 1) / 2) spacing,
  // y0 - (b stride + (stride - 1) / 2) spacing, z0 + c dz
  const double texel_m = stride * g.spacing_m;
  const Vec3 first = frame.to_scene(g.origin_x + (stride - 1) / 2.0 * g.spacing_m,
                                    g.origin_y - (stride - 1) / 2.0 * g.spacing_m, g.z0_m);
  const double dz_scene = g.dz_m * frame.exaggeration;
  tex_scale[0] = static_cast<float>(1.0 / (texel_m * tx));
  tex_offset[0] = static_cast<float>((-first.x() / texel_m + 0.5) / tx);
  tex_scale[1] = static_cast<float>(-1.0 / (texel_m * ty));
  tex_offset[1] = static_cast<float>((first.y() / texel_m + 0.5) / ty);
  tex_scale[2] = static_cast<float>(1.0 / (dz_scene * g.nz));
  tex_offset[2] = static_cast<float>((-first.z() / dz_scene + 0.5) / g.nz);
}

Status Renderer::Impl::build_field_texture(const storage::PackLevel& level, std::size_t max_voxels,
                                           double fp_max_config, SceneInfo& info) {
  const fields::VolumeGeometry& g = level.geometry();
  GLint max_3d = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
  if (g.nz > max_3d) {
    return Status(Errc::unsupported, "the pack's " + std::to_string(g.nz) + " height levels exceed the GL's " +
                                         std::to_string(max_3d) + "-texel 3D textures");
  }
  const int stride = volume_stride(g, max_voxels, max_3d);
  const int tx = texels_of(g.nx, stride), ty = texels_of(g.ny, stride);
  double largest = 0;
  const std::vector<float> mean = averaged_field(level, stride, largest);
  fp_max = fp_max_config > 0 ? fp_max_config : (largest > 0 ? largest : 1.0);
  upload_field(mean, tx, ty, g.nz);
  map_field_texture(g, stride, tx, ty);
  info.fp_max = fp_max;
  info.volume_nx = tx;
  info.volume_ny = ty;
  info.volume_nz = g.nz;
  info.volume_stride = stride;
  return gl_status("uploading the F_p texture");
}

namespace {

GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

// Links a program into `id`; the name goes into the error.
Status link_into(GLuint& id, const char* vertex, const char* fragment, const char* name) {
  Result<GLuint> p = link(vertex, fragment, name);
  if (!p.ok()) return p.status();
  id = *p;
  return Status::ok_status();
}

}  // namespace

Status Renderer::Impl::build_surface_programs() {
  VISVOL_RETURN_IF_ERROR(link_into(terrain.id, detail::kTerrainVertex, detail::kTerrainFragment, "terrain"));
  const GLuint t = terrain.id;
  terrain.view_proj = uniform(t, "u_view_proj");
  terrain.field = uniform(t, "u_field");
  terrain.colour_map = uniform(t, "u_colour_map");
  terrain.tex_scale = uniform(t, "u_tex_scale");
  terrain.tex_offset = uniform(t, "u_tex_offset");
  terrain.mode = uniform(t, "u_mode");
  terrain.height = uniform(t, "u_height");
  terrain.light = uniform(t, "u_light");
  terrain.plain_colour = uniform(t, "u_plain_colour");
  terrain.skirt_colour = uniform(t, "u_skirt_colour");
  VISVOL_RETURN_IF_ERROR(link_into(tube.id, detail::kTubeVertex, detail::kTubeFragment, "tube"));
  tube.view_proj = uniform(tube.id, "u_view_proj");
  tube.inflate = uniform(tube.id, "u_inflate");
  tube.colour_map = uniform(tube.id, "u_colour_map");
  tube.light = uniform(tube.id, "u_light");
  tube.outline = uniform(tube.id, "u_outline");
  tube.outline_colour = uniform(tube.id, "u_outline_colour");
  VISVOL_RETURN_IF_ERROR(link_into(overlay.id, detail::kOverlayVertex, detail::kOverlayFragment, "overlay"));
  overlay.size = uniform(overlay.id, "u_size");
  overlay.colour_map = uniform(overlay.id, "u_colour_map");
  return Status::ok_status();
}

Status Renderer::Impl::build_field_programs() {
  VISVOL_RETURN_IF_ERROR(link_into(volume.id, detail::kFullscreenVertex, detail::kVolumeFragment, "volume"));
  const GLuint v = volume.id;
  volume.inverse = uniform(v, "u_inverse");
  volume.viewport = uniform(v, "u_viewport");
  volume.depth_map = uniform(v, "u_depth_map");
  volume.box_min = uniform(v, "u_box_min");
  volume.box_max = uniform(v, "u_box_max");
  volume.depth = uniform(v, "u_depth");
  volume.field = uniform(v, "u_field");
  volume.colour_map = uniform(v, "u_colour_map");
  volume.tex_scale = uniform(v, "u_tex_scale");
  volume.tex_offset = uniform(v, "u_tex_offset");
  volume.step = uniform(v, "u_step");
  volume.max_steps = uniform(v, "u_max_steps");
  VISVOL_RETURN_IF_ERROR(link_into(composite.id, detail::kFullscreenVertex, detail::kCompositeFragment, "composite"));
  composite.viewport = uniform(composite.id, "u_viewport");
  composite.texture_size = uniform(composite.id, "u_texture_size");
  composite.half = uniform(composite.id, "u_half");
  VISVOL_RETURN_IF_ERROR(link_into(slice.id, detail::kFullscreenVertex, detail::kSliceFragment, "slice"));
  const GLuint c = slice.id;
  slice.viewport = uniform(c, "u_viewport");
  slice.profile = uniform(c, "u_profile");
  slice.field = uniform(c, "u_field");
  slice.colour_map = uniform(c, "u_colour_map");
  slice.tex_scale = uniform(c, "u_tex_scale");
  slice.tex_offset = uniform(c, "u_tex_offset");
  slice.z_top = uniform(c, "u_z_top");
  slice.z_bottom = uniform(c, "u_z_bottom");
  slice.ground_colour = uniform(c, "u_ground_colour");
  return Status::ok_status();
}

Status Renderer::Impl::build_programs() {
  VISVOL_RETURN_IF_ERROR(build_surface_programs());
  VISVOL_RETURN_IF_ERROR(build_field_programs());
  return gl_status("building the shaders");
}

void Renderer::Impl::upload_colour_map(const TransferFunction& tf) {
  // opacity per ray step from opacity per unit length (transfer_function.hpp)
  const Vec3 extent = field_box.max - field_box.min;
  const double unit = kOpacityUnitFraction * std::max(extent.x(), extent.y());
  const double step_units = volume_step / unit;
  std::vector<float> texels(kColourMapTexels * 4);
  for (int i = 0; i < kColourMapTexels; ++i) {
    const double fp = static_cast<double>(i) / (kColourMapTexels - 1);
    const Rgb c = colour_at(tf, fp);
    const std::size_t o = static_cast<std::size_t>(i) * 4;
    texels[o + 0] = static_cast<float>(c.r);
    texels[o + 1] = static_cast<float>(c.g);
    texels[o + 2] = static_cast<float>(c.b);
    texels[o + 3] = static_cast<float>(opacity_for_step(opacity_at(tf, fp), step_units));
  }
  glGenTextures(1, &colour_map_tex);
  glBindTexture(GL_TEXTURE_2D, colour_map_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, kColourMapTexels, 1, 0, GL_RGBA, GL_FLOAT, texels.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

Status Renderer::Impl::build_frame_targets(int w, int h) {
  // the frame: colour and depth renderbuffers; a depth texture the volume
  // pass reads (a copy, so it never samples what is attached for drawing)
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenRenderbuffers(1, &colour_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, colour_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_rb);
  glGenRenderbuffers(1, &depth_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    return Status(Errc::unsupported, "the frame's framebuffer object is incomplete");
  }
  glGenTextures(1, &depth_tex);
  glBindTexture(GL_TEXTURE_2D, depth_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, w, h, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glGenFramebuffers(1, &depth_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, depth_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex, 0);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    return Status(Errc::unsupported, "the depth copy's framebuffer object is incomplete");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return Status::ok_status();
}

Status Renderer::Impl::build_half_target(int w, int h) {
  // the volume of a large frame marches at half resolution into this
  half_width = (w + 1) / 2;
  half_height = (h + 1) / 2;
  glGenTextures(1, &half_tex);
  glBindTexture(GL_TEXTURE_2D, half_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, half_width, half_height, 0, GL_RGBA, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glGenFramebuffers(1, &half_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, half_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, half_tex, 0);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    return Status(Errc::unsupported, "the half-resolution volume's framebuffer object is incomplete");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  // the slice view's profile: one texel per column
  glGenTextures(1, &profile_tex);
  glBindTexture(GL_TEXTURE_2D, profile_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, 1, 0, GL_RGBA, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return Status::ok_status();
}

void Renderer::Impl::build_geometry_buffers(const RendererConfig& config) {
  // the path tube: vertices rewritten per frame, indices fixed
  const std::size_t tube_floats = config.max_path_vertices * detail::kTubeSides * detail::kTubeFloats;
  glGenVertexArrays(1, &tube_vao);
  glBindVertexArray(tube_vao);
  glGenBuffers(1, &tube_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, tube_vbo);
  glBufferData(GL_ARRAY_BUFFER, gl_bytes(tube_floats * sizeof(float)), nullptr, GL_DYNAMIC_DRAW);
  const std::vector<std::uint32_t> indices = detail::tube_indices(config.max_path_vertices);
  glGenBuffers(1, &tube_ibo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, tube_ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, gl_bytes(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  vertex_layout({3, 3, 1});  // position, normal, F_p
  // the overlay: pixel position, colour, F_p
  overlay_capacity = kOverlayBaseVertices + kOverlayVerticesPerPathPoint * config.max_path_vertices +
                     kOverlayVerticesPerMarker * (config.max_markers + 2);
  glGenVertexArrays(1, &overlay_vao);
  glBindVertexArray(overlay_vao);
  glGenBuffers(1, &overlay_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, overlay_vbo);
  glBufferData(GL_ARRAY_BUFFER, gl_bytes(overlay_capacity * detail::kOverlayFloats * sizeof(float)), nullptr,
               GL_DYNAMIC_DRAW);
  vertex_layout({2, 4, 1});
  glGenVertexArrays(1, &empty_vao);
  glBindVertexArray(0);
}

void Renderer::Impl::reserve_scratch(const RendererConfig& config) {
  const auto w = static_cast<std::size_t>(config.max_width_px), h = static_cast<std::size_t>(config.max_height_px);
  centres.resize(config.max_path_vertices);
  fps.resize(config.max_path_vertices);
  arc_m.resize(config.max_path_vertices);
  tube_data.resize(config.max_path_vertices * detail::kTubeSides * detail::kTubeFloats);
  overlay_data.resize(overlay_capacity * detail::kOverlayFloats);
  profile.resize(w * 4);
  pixels.resize(w * h * 4);
}

Status Renderer::Impl::build_buffers(const RendererConfig& config) {
  VISVOL_RETURN_IF_ERROR(build_frame_targets(config.max_width_px, config.max_height_px));
  VISVOL_RETURN_IF_ERROR(build_half_target(config.max_width_px, config.max_height_px));
  build_geometry_buffers(config);
  reserve_scratch(config);
  return gl_status("building the frame buffers");
}

namespace {

Status validate_config(const RendererConfig& c) {
  const auto side_ok = [](int v) { return v >= kMinSidePx && v <= kMaxSidePx; };
  if (!side_ok(c.max_width_px) || !side_ok(c.max_height_px)) {
    return invalid_argument("renderer size " + std::to_string(c.max_width_px) + " x " +
                            std::to_string(c.max_height_px) + " is outside " + std::to_string(kMinSidePx) + ".." +
                            std::to_string(kMaxSidePx) + " pixels a side");
  }
  if (c.max_path_vertices < 2 || c.max_path_vertices > (1u << 20)) {
    return invalid_argument("renderer max_path_vertices " + std::to_string(c.max_path_vertices) +
                            " is outside 2..1048576");
  }
  if (c.max_markers > 1024) {
    return invalid_argument("renderer max_markers " + std::to_string(c.max_markers) + " is above 1024");
  }
  if (!std::isfinite(c.vertical_exaggeration) || c.vertical_exaggeration < 0 || c.vertical_exaggeration > 1000) {
    return invalid_argument("vertical exaggeration " + std::to_string(c.vertical_exaggeration) +
                            " is outside 0 (automatic)..1000");
  }
  if (!std::isfinite(c.fp_max) || c.fp_max < 0 || c.fp_max > 1) {
    return invalid_argument("fp_max " + std::to_string(c.fp_max) + " is outside 0 (the field's largest)..1");
  }
  if (c.max_volume_voxels < 4096) {
    return invalid_argument("max_volume_voxels " + std::to_string(c.max_volume_voxels) + " is under 4096");
  }
  for (float v : c.background_rgb) {
    if (!(v >= 0.0f && v <= 1.0f)) return invalid_argument("background colour component outside [0, 1]");
  }
  return validate(c.transfer, "transfer function");
}

}  // namespace

void Renderer::Impl::load_terrain(const storage::PackLevel& level, double vertical_exaggeration) {
  const fields::VolumeGeometry& g = level.geometry();
  nx = g.nx;
  ny = g.ny;
  spacing_m = g.spacing_m;
  origin_x_m = g.origin_x;
  origin_y_m = g.origin_y;
  top_m = g.top_m();
  heights_m.resize(static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny));
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      heights_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(g.nx) + static_cast<std::size_t>(i)] =
          level.post(i, j);
    }
  }
  // the scene: centred on the terrain, heights from the lowest level up
  const double width_m = (g.nx - 1) * g.spacing_m, depth_m = (g.ny - 1) * g.spacing_m;
  const double tall_m = std::max(g.top_m() - g.z0_m, 1e-3);
  frame.centre_x_m = g.origin_x + width_m / 2;
  frame.centre_y_m = g.origin_y - depth_m / 2;
  frame.z_ref_m = g.z0_m;
  frame.exaggeration = vertical_exaggeration > 0 ? vertical_exaggeration
                                                 : std::clamp(0.2 * std::max(width_m, depth_m) / tall_m, 1.0, 10.0);
  const float lowest = *std::min_element(heights_m.begin(), heights_m.end());
  const float highest = *std::max_element(heights_m.begin(), heights_m.end());
  terrain_box.min = frame.to_scene(g.origin_x, g.origin_y - depth_m, lowest);
  terrain_box.max = frame.to_scene(g.origin_x + width_m, g.origin_y, highest);
  field_box.min = frame.to_scene(g.origin_x, g.origin_y - depth_m, g.z0_m);
  field_box.max = frame.to_scene(g.origin_x + width_m, g.origin_y, g.top_m());
  volume_step = static_cast<float>((field_box.max - field_box.min).norm() / kVolumeStepsPerDiagonal);
  volume_max_steps = static_cast<int>(kVolumeStepsPerDiagonal) + 2;
}

Status Renderer::Impl::build_gl(const storage::PackLevel& level, const RendererConfig& config, SceneInfo& info) {
  Result<std::unique_ptr<GlContext>> made = GlContext::create();
  if (!made.ok()) return made.status();
  context = std::move(*made);
  info.gl_renderer = context->renderer();
  info.gl_version = context->version();
  info.terrain_nx = nx;
  info.terrain_ny = ny;
  info.vertical_exaggeration = frame.exaggeration;
  VISVOL_RETURN_IF_ERROR(build_programs());
  VISVOL_RETURN_IF_ERROR(build_meshes(config.max_width_px, config.max_height_px));
  for (const Mesh& mesh : meshes) info.mesh_steps.push_back(mesh.step);
  VISVOL_RETURN_IF_ERROR(build_field_texture(level, config.max_volume_voxels, config.fp_max, info));
  upload_colour_map(config.transfer);
  VISVOL_RETURN_IF_ERROR(build_buffers(config));
  Result<std::unique_ptr<PngEncoder>> encoder =
      PngEncoder::create(config.max_width_px, config.max_height_px, config.png_compression_level);
  if (!encoder.ok()) return encoder.status();
  png = std::move(*encoder);
  return Status::ok_status();
}

Status Renderer::warm_up() {
  // one small frame of every view compiles llvmpipe's shader variants now,
  // not in the first real frame
  const Impl& m = *impl_;
  const double w_m = (m.nx - 1) * m.spacing_m, h_m = (m.ny - 1) * m.spacing_m;
  const PathPoint path[2] = {{m.origin_x_m + w_m * 0.25, m.origin_y_m - h_m * 0.25, m.top_m, 0.25},
                             {m.origin_x_m + w_m * 0.75, m.origin_y_m - h_m * 0.75, m.top_m, 0.75}};
  const auto frame = [&](View v, int side_px) {
    Frame f;
    f.view = v;
    f.width_px = std::min(side_px, config_.max_width_px);
    f.height_px = std::min(side_px, config_.max_height_px);
    f.path = path;
    f.path_size = 2;
    return render(f).with_context(std::string("warm-up frame (") + to_string(v) + " view)");
  };
  for (View v : {View::top, View::oblique, View::volume, View::slice}) {
    VISVOL_RETURN_IF_ERROR(frame(v, kWarmupSidePx));
  }
  return frame(View::volume, 400);  // the half-resolution volume, where allowed
}

Result<std::unique_ptr<Renderer>> Renderer::create(std::shared_ptr<const storage::Pack> pack,
                                                   const RendererConfig& config) {
  VISVOL_RETURN_IF_ERROR(validate_config(config));
  if (!pack) return invalid_argument("renderer: no pack");
  Result<storage::PackLevel> level = storage::PackLevel::open(pack, 0);
  if (!level.ok()) return level.status();
  const fields::VolumeGeometry& g = level->geometry();
  if (g.nx < 2 || g.ny < 2 || g.nz < 2) return invalid_argument(pack->path() + ": level 0 is smaller than 2 x 2 x 2");

  std::unique_ptr<Renderer> r(new Renderer());
  r->config_ = config;
  r->impl_ = std::make_unique<Impl>();
  r->impl_->pack = pack;
  r->impl_->load_terrain(*level, config.vertical_exaggeration);
  VISVOL_RETURN_IF_ERROR(r->impl_->build_gl(*level, config, r->info_));
  VISVOL_RETURN_IF_ERROR(r->warm_up());
  return r;
}

Renderer::~Renderer() = default;  // the context owns every GL object and frees them with itself

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

Image Renderer::image() const {
  Image im;
  im.rgba = impl_->pixels.data();
  im.width_px = impl_->width;
  im.height_px = impl_->height;
  im.stride_bytes = static_cast<std::size_t>(impl_->width) * 4;
  return im;
}

Result<std::size_t> Renderer::encode_png(std::uint8_t* out, std::size_t capacity_bytes) {
  if (impl_->width == 0) return Status(Errc::state, "encode_png: no frame rendered yet");
  const Image im = image();
  return impl_->png->encode(im.rgba, im.width_px, im.height_px, im.stride_bytes, out, capacity_bytes);
}

std::optional<PixelPoint> Renderer::project(double x_m, double y_m, double z_m) const {
  if (impl_->width == 0 || impl_->view == View::slice) return std::nullopt;
  return impl_->camera.project(impl_->frame.to_scene(x_m, y_m, z_m));
}

std::optional<PixelPoint> Renderer::slice_pixel(double distance_m, double z_m) const {
  if (impl_->width == 0 || impl_->view != View::slice) return std::nullopt;
  return impl_->slice_point(layout_.scene, distance_m, z_m);
}

}  // namespace visvol::render
