// Synthetic terrains for the field tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "fields/heightfield.hpp"

namespace visvol::fields::testing {

inline Heightfield blank(int nx, int ny, double spacing_m, float height_m = 100.0f) {
  Heightfield hf;
  hf.nx = nx;
  hf.ny = ny;
  hf.spacing_m = spacing_m;
  hf.origin_x = 500000.0;
  hf.origin_y = 4000000.0;
  hf.height_m.assign(hf.size(), height_m);
  return hf;
}

inline Heightfield flat(int n, double spacing_m = 10.0) { return blank(n, n, spacing_m); }

// A north-south wall of the given height in column `column`.
inline Heightfield wall(int n, int column, float wall_height_m, double spacing_m = 10.0) {
  Heightfield hf = blank(n, n, spacing_m);
  for (int j = 0; j < n; ++j) hf.at(column, j) += wall_height_m;
  return hf;
}

// The paper's synthetic terrain (Fig. 7): two parallel triangular prisms along
// the length of a flat square, near its centre, with a valley between them.
inline Heightfield two_prisms(int n, double spacing_m = 10.0, float ridge_m = 60.0f) {
  Heightfield hf = blank(n, n, spacing_m, 0.0f);
  const double half_width = n / 10.0;
  const double c1 = n * 0.38, c2 = n * 0.62;
  for (int j = n / 8; j < n - n / 8; ++j) {
    for (int i = 0; i < n; ++i) {
      const double d = std::min(std::fabs(i - c1), std::fabs(i - c2));
      if (d < half_width) hf.at(i, j) = static_cast<float>(ridge_m * (1.0 - d / half_width));
    }
  }
  return hf;
}

// Fractal (fBm) noise from a few octaves of random sines; deterministic per seed.
inline Heightfield fractal(int n, std::uint32_t seed, double spacing_m = 30.0, double relief_m = 300.0) {
  Heightfield hf = blank(n, n, spacing_m, 0.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double two_pi = 6.283185307179586;
  struct Wave {
    double kx, ky, phase, amp;
  };
  std::vector<Wave> waves;
  double amp = 1.0;
  for (int octave = 0; octave < 6; ++octave) {
    for (int w = 0; w < 4; ++w) {
      const double angle = two_pi * u(rng);
      const double freq = (1 << octave) * two_pi / n;
      waves.push_back({freq * std::cos(angle), freq * std::sin(angle), two_pi * u(rng), amp});
    }
    amp *= 0.5;
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      double h = 0;
      for (const Wave& w : waves) h += w.amp * std::sin(w.kx * i + w.ky * j + w.phase);
      hf.at(i, j) = static_cast<float>(500.0 + relief_m * 0.25 * h);
    }
  }
  return hf;
}

// A crop of a real heightfield (keeps the georeference).
inline Heightfield crop(const Heightfield& src, int i0, int j0, int nx, int ny) {
  Heightfield hf;
  hf.nx = nx;
  hf.ny = ny;
  hf.spacing_m = src.spacing_m;
  hf.origin_x = src.x_of(i0);
  hf.origin_y = src.y_of(j0);
  hf.crs_wkt = src.crs_wkt;
  hf.height_m.resize(hf.size());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) hf.at(i, j) = src.at(i0 + i, j0 + j);
  }
  return hf;
}

inline std::string test_data(const std::string& name) { return std::string(VISVOL_TEST_DATA) + "/" + name; }

}  // namespace visvol::fields::testing
