// The renderer's set-up: create() and its warm-up, the configuration's
// checks, and what create() builds once (GL programs, the terrain meshes, the
// F_p and colour-map textures, the frame targets and every per-frame buffer).
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <utility>

#include "drivers/render/renderer.hpp"
#include "drivers/render/renderer_impl.hpp"
#include "drivers/render/scene.hpp"
#include "drivers/render/shaders.hpp"

namespace visvol::render {

using detail::gl_bytes;
using detail::gl_count;
using detail::gl_offset;
using detail::gl_status;
using detail::Vec3;

namespace {

// Samples along the volume box's diagonal: the ray-marching step.
constexpr double kVolumeStepsPerDiagonal = 256;
constexpr int kColourMapTexels = 256;
constexpr int kWarmupSidePx = 64;
// Overlay vertices beyond the path and markers: text, bars, arrow (measured
// under 4000 at 4096 x 4096; the tests check nothing is dropped).
constexpr std::size_t kOverlayBaseVertices = 16384;
constexpr std::size_t kOverlayVerticesPerPathPoint = 12;  // slice view: outline and line
constexpr std::size_t kOverlayVerticesPerMarker = 300;    // stalk, rim and fill

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

}  // namespace

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
std::vector<float> averaged_field(const storage::CachedLevel& level, int stride, double& largest) {
  const fields::VolumeGeometry& g = level.geometry();
  const int tx = texels_of(g.nx, stride), ty = texels_of(g.ny, stride);
  const std::size_t layer = static_cast<std::size_t>(tx) * static_cast<std::size_t>(ty);
  std::vector<float> mean(layer * static_cast<std::size_t>(g.nz));
  largest = 0;
  // a texel column at a time, all its levels: the bricks it reads stay in the level's cache
  for (int bj = 0; bj < ty; ++bj) {
    for (int bi = 0; bi < tx; ++bi) {
      for (int k = 0; k < g.nz; ++k) {
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
        mean[static_cast<std::size_t>(k) * layer + static_cast<std::size_t>(bj) * static_cast<std::size_t>(tx) +
             static_cast<std::size_t>(bi)] = static_cast<float>(sum / count);
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

Status Renderer::Impl::build_field_texture(const storage::CachedLevel& level, std::size_t max_voxels,
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

void Renderer::Impl::load_terrain(const storage::CachedLevel& level, double vertical_exaggeration) {
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

Status Renderer::Impl::build_gl(const storage::CachedLevel& level, const RendererConfig& config, SceneInfo& info) {
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
  // copies, never the mapping (a console's pack may be replaced under it);
  // every brick is checked as it is read
  // (the texture is averaged a texel column at a time along texel rows: two
  // rows of bricks held keep every brick read once where a texel is at most
  // a brick wide)
  const int bricks_x = (pack->geometry(0).nx + storage::kBrickPosts - 1) / storage::kBrickPosts;
  Result<storage::CachedLevel> level = storage::CachedLevel::open(pack, 0, 2 * bricks_x + 4);
  if (!level.ok()) return level.status();
  const fields::VolumeGeometry& g = level->geometry();
  if (g.nx < 2 || g.ny < 2 || g.nz < 2) return invalid_argument(pack->path() + ": level 0 is smaller than 2 x 2 x 2");

  std::unique_ptr<Renderer> r(new Renderer());
  r->config_ = config;
  r->impl_ = std::make_unique<Impl>();
  r->impl_->pack = std::move(pack);
  r->impl_->load_terrain(*level, config.vertical_exaggeration);
  VISVOL_RETURN_IF_ERROR(r->impl_->build_gl(*level, config, r->info_));
  if (level->read_failures() > 0) return level->last_status();
  VISVOL_RETURN_IF_ERROR(r->warm_up());
  return r;
}

}  // namespace visvol::render
