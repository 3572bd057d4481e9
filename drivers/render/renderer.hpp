// Thumbnails of a plan: the terrain, its visibility field F_p and the path,
// drawn offscreen with OpenGL 3.3 core and encoded as PNG.
//
// Views (Frame::view):
//   top      orthographic, north up: the terrain as a lit mesh decimated to
//            the thumbnail's resolution, coloured by F_p at the path's mean
//            altitude (grey where the terrain is above it) or at a chosen
//            height above the ground; the path as a tube coloured by F_p
//            along it (dark outline); start (green disc) and end (white
//            square) markers; hidden-from (black diamond) and visible-to
//            (magenta diamond) points; colour bar, north arrow, scale bar.
//   oblique  the same in perspective from the south-south-west, 35 degrees
//            up, heights exaggerated (RendererConfig); markers on stalks.
//   volume   the paper's Fig. 3: F_p volume-rendered above the terrain (ray
//            marching a 3D texture of F_p through the transfer function),
//            the terrain (plain grey) and the path composited in.
//   slice    a vertical slice of F_p along the path: distance along the path
//            across, height up, the terrain below the profile, the path.
// Colours of F_p everywhere come from the transfer function's colour ramp,
// F_p scaled by the top of the colour scale (RendererConfig::fp_max).
//
// Model and data: create() reads the pack once (level 0's terrain into mesh
// buffers at a few decimations, level 0's F_p into a 3D texture within a
// voxel budget), compiles the shaders, makes the framebuffers at the largest
// size and reserves every per-frame buffer. render() and encode_png() then
// allocate nothing on the heap (a counting allocator checks this in the
// tests); frames smaller than the maximum use a corner of the same buffers.
//
// Threads: a Renderer is used by one thread at a time (the console's
// renderer thread, never the real-time thread: a frame takes milliseconds
// to hundreds of milliseconds). Its GL context is made current on the calling
// thread at create() and again by render() if another context was current.
//
// Errors: create() fails with a message naming the problem. render() and
// encode_png() return a Status whose message names the bad field ("path
// vertex 12: F_p nan is outside [0, 1]"); they allocate only to build that
// message. Nothing is thrown.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/status.hpp"
#include "drivers/render/transfer_function.hpp"
#include "storage/pack_reader.hpp"

namespace visvol::render {

enum class View : std::uint8_t { top, oblique, volume, slice };
const char* to_string(View view);
// "top", "oblique", "volume", "slice"; invalid_argument naming the text otherwise.
Result<View> parse_view(const std::string& text);

inline constexpr int kMinSidePx = 32;
inline constexpr int kMaxSidePx = 4096;
// The console's path sample holds at most this many vertices (msg::kMaxPathVertices).
inline constexpr std::size_t kDefaultMaxPathVertices = 512;
inline constexpr std::size_t kDefaultMaxMarkers = 16;
// F_p is shown this high above the ground when there is no path and no height.
inline constexpr double kDefaultHeightAboveGroundM = 30.0;

// One path vertex: world metres in the pack's CRS (z above the DEM's datum)
// and F_p there (dimensionless, [0, 1]).
struct PathPoint {
  double x_m, y_m, z_m;
  double fp;
};

enum class MarkerKind : std::uint8_t { hidden_from, visible_to };
struct Marker {
  MarkerKind kind;
  double x_m, y_m, z_m;
};

struct Frame {
  View view = View::oblique;
  int width_px = 256, height_px = 256;  // kMinSidePx..the renderer's maximum
  const PathPoint* path = nullptr;      // 0 or at least 2 vertices; the slice view needs a path
  std::size_t path_size = 0;
  const Marker* markers = nullptr;
  std::size_t marker_count = 0;
  // Terrain colour: F_p this high above the ground; unset: F_p at the path's
  // mean altitude, or kDefaultHeightAboveGroundM without a path.
  std::optional<double> height_above_ground_m;
};

struct RendererConfig {
  int max_width_px = 1024;  // framebuffers and readback are made this size once
  int max_height_px = 768;
  std::size_t max_path_vertices = kDefaultMaxPathVertices;
  std::size_t max_markers = kDefaultMaxMarkers;
  int png_compression_level = 1;  // zlib 0..9 (1: a third of the cost of 6)
  // Height scale of the 3D views; 0: automatic (the field volume a fifth as
  // tall as it is wide, between 1 and 10).
  double vertical_exaggeration = 0.0;
  // Voxels of the F_p 3D texture at most (one byte each): level 0's F_p is
  // averaged over s x s posts, s the smallest that fits.
  std::size_t max_volume_voxels = 8u << 20;
  // Top of the colour scale, F_p: the transfer function's F = 1 is this F_p.
  // 0: the largest F_p of level 0 (F_p is a fraction of all the terrain's
  // area, so a limited range keeps it well under 1). Give one value to
  // compare pictures of several packs.
  double fp_max = 0.0;
  TransferFunction transfer = default_transfer_function();
  float background_rgb[3] = {0.110f, 0.122f, 0.153f};
};

struct PixelRect {
  int x = 0, y = 0;  // top-left corner, pixels from the image's top-left
  int width = 0, height = 0;
};

// Where things are in the last frame (pixels, x right, y down).
struct FrameLayout {
  int width_px = 0, height_px = 0;
  PixelRect scene;                           // the 3D scene or the slice panel
  PixelRect colour_bar;                      // F_p 0 at the bottom row, 1 at the top row
  double metres_per_px = 0;                  // horizontal scale at the terrain's centre (slice: along the path)
  double scale_bar_m = 0;                    // the scale bar's length
  std::size_t overlay_vertices_dropped = 0;  // always 0 unless the overlay's reserve is too small (a bug)
};

// What create() made of the pack (for logs and tests).
struct SceneInfo {
  int terrain_nx = 0, terrain_ny = 0;  // level 0 posts
  std::vector<int> mesh_steps;         // post strides of the prepared meshes, finest first
  int volume_nx = 0, volume_ny = 0, volume_nz = 0;
  int volume_stride = 1;  // posts averaged per texel side
  double vertical_exaggeration = 1.0;
  double fp_max = 1.0;  // F_p at the top of the colour scale
  std::string gl_renderer, gl_version;
};

struct PixelPoint {
  double x, y;  // pixel coordinates of the point's centre (x right, y down)
};

// A decoded view of the last frame: RGBA8, top row first.
struct Image {
  const std::uint8_t* rgba = nullptr;
  int width_px = 0, height_px = 0;
  std::size_t stride_bytes = 0;
  const std::uint8_t* pixel(int x, int y) const {
    return rgba + static_cast<std::size_t>(y) * stride_bytes + static_cast<std::size_t>(x) * 4;
  }
};

class Renderer {
 public:
  // Reads the pack's level 0 and prepares everything (tens to hundreds of
  // ms: mesh, 3D texture, shader compilation, one warm-up frame per view).
  static Result<std::unique_ptr<Renderer>> create(std::shared_ptr<const storage::Pack> pack,
                                                  const RendererConfig& config);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws one frame and reads it back. No allocation on success.
  Status render(const Frame& frame);

  // The last frame's pixels (valid until the next render()).
  Image image() const;
  const FrameLayout& layout() const { return layout_; }

  // Encodes the last frame as PNG into out[0, capacity_bytes); returns its
  // size. A msg::ThumbnailSample's png array (kMaxThumbnailBytes) is a valid
  // target. No allocation on success.
  Result<std::size_t> encode_png(std::uint8_t* out, std::size_t capacity_bytes);

  // Where a world point lands in the last frame of a 3D view; nullopt in the
  // slice view or behind the camera.
  std::optional<PixelPoint> project(double x_m, double y_m, double z_m) const;
  // Where (distance along the path, height) lands in the last slice frame.
  std::optional<PixelPoint> slice_pixel(double distance_m, double z_m) const;

  const SceneInfo& scene_info() const { return info_; }
  const RendererConfig& config() const { return config_; }

  struct Impl;

 private:
  Renderer() = default;
  Status warm_up();
  RendererConfig config_;
  SceneInfo info_;
  FrameLayout layout_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace visvol::render
