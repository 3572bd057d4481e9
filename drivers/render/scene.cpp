#include "drivers/render/scene.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "base/angles.hpp"

namespace visvol::render::detail {

namespace {

constexpr double kFitFraction = 0.94;  // of the viewport's half-size the fitted box may span

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = (target - eye).normalized();
  const Vec3 s = f.cross(up).normalized();
  const Vec3 u = s.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4 perspective(double fovy_rad, double aspect, double near_m, double far_m) {
  const double f = 1.0 / std::tan(fovy_rad / 2);
  Mat4 m = Mat4::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (far_m + near_m) / (near_m - far_m);
  m(2, 3) = 2 * far_m * near_m / (near_m - far_m);
  m(3, 2) = -1;
  return m;
}

Mat4 ortho(double half_w, double half_h, double near_m, double far_m) {
  Mat4 m = Mat4::Identity();
  m(0, 0) = 1 / half_w;
  m(1, 1) = 1 / half_h;
  m(2, 2) = -2 / (far_m - near_m);
  m(2, 3) = -(far_m + near_m) / (far_m - near_m);
  return m;
}

std::array<Vec3, 8> corners(const Box& b) {
  std::array<Vec3, 8> c;
  for (int n = 0; n < 8; ++n) {
    c[static_cast<std::size_t>(n)] =
        Vec3((n & 1) ? b.max.x() : b.min.x(), (n & 2) ? b.max.y() : b.min.y(), (n & 4) ? b.max.z() : b.min.z());
  }
  return c;
}

// Shifts and scales NDC x, y uniformly (a pan and zoom, the aspect kept) so
// the box's projection is centred and spans kFitFraction of the viewport,
// then flips y (see Camera).
Camera fitted(const Mat4& view_proj, const Box& box, const PixelRect& viewport, bool perspective_camera,
              const Vec3& eye) {
  double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
  for (const Vec3& c : corners(box)) {
    const Eigen::Vector4d clip = view_proj * c.homogeneous();
    const double x = clip.x() / clip.w(), y = clip.y() / clip.w();
    lo_x = std::min(lo_x, x);
    hi_x = std::max(hi_x, x);
    lo_y = std::min(lo_y, y);
    hi_y = std::max(hi_y, y);
  }
  const double cx = (lo_x + hi_x) / 2, cy = (lo_y + hi_y) / 2;
  const double half = std::max({(hi_x - lo_x) / 2, (hi_y - lo_y) / 2, 1e-12});
  const double s = kFitFraction / half;
  Mat4 fit = Mat4::Identity();
  fit(0, 0) = s;
  fit(1, 1) = s;
  fit(0, 3) = -s * cx;
  fit(1, 3) = -s * cy;
  Mat4 flip = Mat4::Identity();
  flip(1, 1) = -1;
  Camera cam;
  cam.view_proj = flip * fit * view_proj;
  cam.inverse = cam.view_proj.inverse();
  cam.viewport = viewport;
  cam.perspective = perspective_camera;
  cam.eye = eye;
  return cam;
}

double aspect_of(const PixelRect& r) { return static_cast<double>(r.width) / std::max(1, r.height); }

}  // namespace

std::optional<PixelPoint> Camera::project(const Vec3& scene) const {
  const Eigen::Vector4d clip = view_proj * scene.homogeneous();
  if (clip.w() <= 1e-12) return std::nullopt;
  const double x = clip.x() / clip.w(), y = clip.y() / clip.w();
  return PixelPoint{viewport.x + (x + 1) / 2 * viewport.width, viewport.y + (y + 1) / 2 * viewport.height};
}

Camera top_camera(const Box& box, const PixelRect& viewport) {
  const Vec3 centre = (box.min + box.max) / 2;
  const double height = box.max.z() - box.min.z();
  const Vec3 eye(centre.x(), centre.y(), box.max.z() + height + 1.0);
  const Mat4 view = look_at(eye, Vec3(centre.x(), centre.y(), box.min.z()), Vec3::UnitY());
  const double depth = eye.z() - box.min.z();
  const Mat4 proj = ortho(aspect_of(viewport), 1.0, 0.5, depth + 1.0);
  return fitted(proj * view, box, viewport, false, eye);
}

Camera oblique_camera(const Box& box, const PixelRect& viewport) {
  const Vec3 centre = (box.min + box.max) / 2;
  const double radius = std::max((box.max - box.min).norm() / 2, 1e-3);
  const double distance = 2.5 * radius;
  const double azimuth = 200.0 * kPi / 180.0, elevation = 35.0 * kPi / 180.0;
  const Vec3 eye = centre + distance * Vec3(std::cos(elevation) * std::sin(azimuth),
                                            std::cos(elevation) * std::cos(azimuth), std::sin(elevation));
  const Mat4 view = look_at(eye, centre, Vec3::UnitZ());
  const Mat4 proj =
      perspective(30.0 * kPi / 180.0, aspect_of(viewport), distance - 1.1 * radius, distance + 1.1 * radius);
  return fitted(proj * view, box, viewport, true, eye);
}

BaseLayout base_layout(int width_px, int height_px) {
  BaseLayout b;
  const int small = std::min(width_px, height_px);
  b.margin_px = std::max(3, static_cast<int>(std::lround(small * 0.025)));
  b.text_scale = std::max(1, small / 256);
  FrameLayout& l = b.layout;
  l.width_px = width_px;
  l.height_px = height_px;
  const int bar_w = std::max(8, static_cast<int>(std::lround(width_px * 0.03)));
  const int label_w = 5 * 6 * b.text_scale + 2 * b.text_scale;  // "0.097" and a gap
  l.colour_bar.width = bar_w;
  l.colour_bar.x = width_px - b.margin_px - bar_w;
  l.colour_bar.y = static_cast<int>(std::lround(height_px * 0.15));
  l.colour_bar.height = static_cast<int>(std::lround(height_px * 0.85)) - l.colour_bar.y;
  l.scene.x = b.margin_px;
  l.scene.y = b.margin_px;
  l.scene.width = std::max(1, l.colour_bar.x - label_w - 2 * b.margin_px);
  l.scene.height = std::max(1, height_px - 2 * b.margin_px);
  return b;
}

double nice_length_m(double max_m) {
  if (!(max_m > 0)) return 0;
  const double decade = std::pow(10.0, std::floor(std::log10(max_m)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * decade <= max_m * (1 + 1e-9)) return m * decade;
  }
  return decade;
}

void length_label(double metres, char* out, std::size_t n) {
  if (metres >= 1000) {
    std::snprintf(out, n, "%g km", metres / 1000);
  } else if (metres >= 1) {
    std::snprintf(out, n, "%.0f m", metres);
  } else {
    std::snprintf(out, n, "%g m", metres);
  }
}

std::vector<int> mesh_samples(int n, int step) {
  std::vector<int> s;
  for (int i = 0; i < n; i += step) s.push_back(i);
  if (s.back() != n - 1) s.push_back(n - 1);
  return s;
}

TerrainMesh terrain_mesh(const std::vector<float>& heights_m, int nx, int ny, int step, double spacing_m,
                         double origin_x_m, double origin_y_m, const SceneFrame& frame, double skirt_bottom) {
  TerrainMesh m;
  m.step = step;
  const std::vector<int> si = mesh_samples(nx, step), sj = mesh_samples(ny, step);
  m.nx = static_cast<int>(si.size());
  m.ny = static_cast<int>(sj.size());
  const auto at = [&](int a, int b) {
    const int i = si[static_cast<std::size_t>(a)], j = sj[static_cast<std::size_t>(b)];
    return frame.to_scene(
        origin_x_m + i * spacing_m, origin_y_m - j * spacing_m,
        heights_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)]);
  };
  const auto push = [&](const Vec3& p, const Vec3& n, double skirt) {
    for (double v : {p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), skirt}) m.vertices.push_back(static_cast<float>(v));
  };
  const std::size_t surface = static_cast<std::size_t>(m.nx) * static_cast<std::size_t>(m.ny);
  const std::size_t rim = 2 * static_cast<std::size_t>(m.nx + m.ny);
  m.vertices.reserve((surface + 2 * rim) * kTerrainFloats);
  for (int b = 0; b < m.ny; ++b) {
    for (int a = 0; a < m.nx; ++a) {
      const Vec3 dx = at(std::min(a + 1, m.nx - 1), b) - at(std::max(a - 1, 0), b);
      const Vec3 dy = at(a, std::min(b + 1, m.ny - 1)) - at(a, std::max(b - 1, 0));
      Vec3 normal = dx.cross(dy);
      if (normal.z() < 0) normal = -normal;  // rows run south: keep the normal pointing up
      push(at(a, b), normal.norm() > 0 ? normal.normalized() : Vec3::UnitZ(), 0.0);
    }
  }
  m.indices.reserve(static_cast<std::size_t>(m.nx - 1) * static_cast<std::size_t>(m.ny - 1) * 6 + rim * 6);
  const auto index = [&](int a, int b) { return static_cast<std::uint32_t>(b * m.nx + a); };
  for (int b = 0; b + 1 < m.ny; ++b) {
    for (int a = 0; a + 1 < m.nx; ++a) {
      for (std::uint32_t v :
           {index(a, b), index(a, b + 1), index(a + 1, b), index(a + 1, b), index(a, b + 1), index(a + 1, b + 1)}) {
        m.indices.push_back(v);
      }
    }
  }
  // skirt: each edge as a strip of (top, bottom) pairs with an outward normal
  const auto wall = [&](int a0, int b0, int da, int db, int count, const Vec3& outward) {
    const auto first = static_cast<std::uint32_t>(m.vertices.size() / kTerrainFloats);
    for (int c = 0; c < count; ++c) {
      const Vec3 top = at(a0 + c * da, b0 + c * db);
      push(top, outward, 1.0);
      push(Vec3(top.x(), top.y(), std::min(skirt_bottom, top.z())), outward, 1.0);
    }
    for (int c = 0; c + 1 < count; ++c) {
      const std::uint32_t t0 = first + 2 * static_cast<std::uint32_t>(c), b0v = t0 + 1, t1 = t0 + 2, b1 = t0 + 3;
      for (std::uint32_t v : {t0, b0v, t1, t1, b0v, b1}) m.indices.push_back(v);
    }
  };
  wall(0, 0, 1, 0, m.nx, Vec3::UnitY());          // north
  wall(0, m.ny - 1, 1, 0, m.nx, -Vec3::UnitY());  // south
  wall(0, 0, 0, 1, m.ny, -Vec3::UnitX());         // west
  wall(m.nx - 1, 0, 0, 1, m.ny, Vec3::UnitX());   // east
  return m;
}

std::vector<int> mesh_steps(int finest, int posts_across) {
  std::vector<int> steps = {std::max(1, finest)};
  while (static_cast<int>(steps.size()) < kMaxMeshes) {
    const int next = std::max(steps.back() + 1, static_cast<int>(std::lround(steps.back() * 1.5)));
    if ((posts_across - 1) / next < kMinMeshCells) break;  // coarser adds nothing useful
    steps.push_back(next);
  }
  return steps;
}

int choose_mesh_step(const std::vector<int>& steps, double px_per_post, double px_per_vertex) {
  const double wanted = px_per_post > 0 ? std::max(1.0, px_per_vertex / px_per_post) : 1.0;
  int chosen = steps.front();
  for (int s : steps) {
    if (s <= wanted) chosen = s;
  }
  return chosen;
}

void tube_vertices(const Vec3* centres, const float* fp, std::size_t count, double radius, float* out) {
  Vec3 normal = Vec3::Zero();
  Vec3 last_tangent = Vec3::UnitX();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3& next = centres[std::min(i + 1, count - 1)];
    const Vec3& prev = centres[i == 0 ? 0 : i - 1];
    Vec3 t = next - prev;
    t = t.norm() > 1e-9 ? t.normalized() : last_tangent;
    last_tangent = t;
    // parallel transport of the ring's frame, so the tube does not twist
    normal -= normal.dot(t) * t;
    if (normal.norm() < 1e-6) {
      normal = t.cross(std::fabs(t.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX());
    }
    normal.normalize();
    const Vec3 binormal = t.cross(normal);
    for (int k = 0; k < kTubeSides; ++k) {
      const double angle = 2 * kPi * k / kTubeSides;
      const Vec3 n = std::cos(angle) * normal + std::sin(angle) * binormal;
      const Vec3 p = centres[i] + radius * n;
      float* v = out + (i * kTubeSides + static_cast<std::size_t>(k)) * kTubeFloats;
      v[0] = static_cast<float>(p.x());
      v[1] = static_cast<float>(p.y());
      v[2] = static_cast<float>(p.z());
      v[3] = static_cast<float>(n.x());
      v[4] = static_cast<float>(n.y());
      v[5] = static_cast<float>(n.z());
      v[6] = fp[i];
    }
  }
}

std::vector<std::uint32_t> tube_indices(std::size_t max_points) {
  std::vector<std::uint32_t> idx;
  if (max_points < 2) return idx;
  idx.reserve((max_points - 1) * kTubeSides * 6);
  const auto S = static_cast<std::uint32_t>(kTubeSides);
  for (std::uint32_t i = 0; i + 1 < max_points; ++i) {
    for (std::uint32_t k = 0; k < S; ++k) {
      const std::uint32_t a = i * S + k, b = i * S + (k + 1) % S, c = a + S, d = b + S;
      for (std::uint32_t v : {a, c, b, b, c, d}) idx.push_back(v);
    }
  }
  return idx;
}

}  // namespace visvol::render::detail
