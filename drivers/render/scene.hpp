// The renderer's geometry on the CPU, kept apart from GL so it can be tested
// alone: world <-> scene coordinates, cameras that fit the terrain into the
// picture, the picture's layout, nice scale-bar lengths, terrain mesh
// decimation, and the path tube.
//
// Scene coordinates: metres east and north of the terrain's centre, and
// height above the field's lowest level times the vertical exaggeration
// (small numbers, so single-precision GL is exact enough).
//
// Pure functions and plain values; thread-safe. Functions marked "no
// allocation" write into caller-reserved arrays (the renderer's frame path).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "drivers/render/renderer.hpp"

namespace visvol::render::detail {

using Mat4 = Eigen::Matrix4d;
using Vec3 = Eigen::Vector3d;

struct SceneFrame {
  double centre_x_m = 0, centre_y_m = 0;  // world point at the scene origin
  double z_ref_m = 0;                     // world height at scene z = 0
  double exaggeration = 1;                // scene z per world metre of height

  Vec3 to_scene(double x_m, double y_m, double z_m) const {
    return {x_m - centre_x_m, y_m - centre_y_m, (z_m - z_ref_m) * exaggeration};
  }
};

struct Box {
  Vec3 min = Vec3::Zero(), max = Vec3::Zero();
};

// A camera fitted to a viewport. Clip space has y flipped (NDC y = -1 is the
// viewport's top row), so GL's window rows run top to bottom and glReadPixels
// returns the image top row first.
struct Camera {
  Mat4 view_proj = Mat4::Identity();  // scene -> clip
  Mat4 inverse = Mat4::Identity();    // clip -> scene
  PixelRect viewport;
  Vec3 eye = Vec3::Zero();  // scene position (perspective cameras)
  bool perspective = false;

  // Pixel position of a scene point; nullopt behind the camera.
  std::optional<PixelPoint> project(const Vec3& scene) const;
};

// North up, looking straight down, the box's footprint fitted into the viewport.
Camera top_camera(const Box& box, const PixelRect& viewport);
// From the south-south-west (azimuth 200 degrees), 35 degrees above the
// horizon, 30-degree vertical field of view, the whole box fitted.
Camera oblique_camera(const Box& box, const PixelRect& viewport);

// Scene rectangle, colour bar and text scale for an image size.
struct BaseLayout {
  FrameLayout layout;
  int margin_px = 0;
  int text_scale = 1;  // font pixels per glyph pixel
};
BaseLayout base_layout(int width_px, int height_px);

// The largest 1, 2 or 5 x 10^k metres not above max_m (max_m > 0).
double nice_length_m(double max_m);

// Text of a length: "500 m", "2 km", "1.5 km". Writes at most n-1 chars plus NUL.
void length_label(double metres, char* out, std::size_t n);

// Terrain mesh of a heightfield sampled every `step` posts (the last row and
// column always included), with normals from central differences at that
// step, and a skirt: walls from the mesh's edges down to scene height
// `skirt_bottom`, so the terrain reads as a solid block and rays of the volume
// view stop at its sides. Vertex: x, y, z, nx, ny, nz (scene coordinates),
// skirt (1 on the walls, 0 on the surface); triangles as indices. Allocates
// (create() only).
inline constexpr int kTerrainFloats = 7;
struct TerrainMesh {
  int step = 1, nx = 0, ny = 0;  // posts per side of the mesh
  std::vector<float> vertices;   // kTerrainFloats per vertex
  std::vector<std::uint32_t> indices;
};
// heights_m: nx x ny posts, row j (southward) after row j - 1; origin: the
// world position of post (0, 0), the north-west post.
TerrainMesh terrain_mesh(const std::vector<float>& heights_m, int nx, int ny, int step, double spacing_m,
                         double origin_x_m, double origin_y_m, const SceneFrame& frame, double skirt_bottom);

// The posts of a mesh side sampled every `step` (0, step, 2 step, ..., n - 1).
std::vector<int> mesh_samples(int n, int step);

// Post strides of the meshes to prepare: `finest`, then each about 1.5 times
// the last (so a frame's chosen mesh has one vertex per 2 to 3 pixels, not
// the 4 pixels of doubling strides), while the mesh keeps more than
// kMinMeshCells cells across `posts_across` posts; at most kMaxMeshes.
inline constexpr int kMinMeshCells = 8;
inline constexpr int kMaxMeshes = 12;
std::vector<int> mesh_steps(int finest, int posts_across);

// The mesh stride to draw for a frame: the coarsest prepared one with at
// least one vertex per px_per_vertex x px_per_vertex pixels of the terrain's
// picture. px_per_post is a post spacing's length on screen (in a perspective
// view, the geometric mean of the east and north spacings at the terrain's
// centre, so the foreshortened direction counts).
int choose_mesh_step(const std::vector<int>& steps, double px_per_post, double px_per_vertex = 2.0);

// Tube around a polyline: kTubeSides vertices a ring, one ring per point;
// vertex = x, y, z, nx, ny, nz, fp (7 floats). Writes points * kTubeSides *
// 7 floats to `out`. No allocation.
inline constexpr int kTubeSides = 8;
inline constexpr int kTubeFloats = 7;
void tube_vertices(const Vec3* centres, const float* fp, std::size_t count, double radius, float* out);
// Indices of the quads between consecutive rings (6 per side per segment).
std::vector<std::uint32_t> tube_indices(std::size_t max_points);

}  // namespace visvol::render::detail
