#include "fields/visibility_builder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <thread>

#include "fields/exact_visibility.hpp"
#include "fields/gdal/dem_io.hpp"
#include "fields/hull_kernel.hpp"
#include "terrains.hpp"
#include "tests/support/local_row_exchange.hpp"

namespace visvol::fields {
namespace {

using namespace visvol::fields::testing;

DenseVolume build(const Heightfield& hf, const FieldParams& p) {
  Result<DenseVolume> v = build_visibility_dense(hf, p);
  EXPECT_TRUE(v.ok()) << v.status().message();
  return v.ok() ? std::move(*v) : DenseVolume{};
}

// The accuracy criterion of the field: at a voxel at least one level above the
// terrain, F_p lies between the exact values one level below and one above,
// within 0.5% of the total area.
struct Accuracy {
  int sampled = 0;
  int within = 0;
  double fraction() const { return sampled ? double(within) / sampled : 0.0; }
};

Accuracy check_against_exact(const Heightfield& hf, const FieldParams& p, const DenseVolume& f, int samples,
                             std::uint32_t seed) {
  const std::vector<float> area = area_factor(hf);
  const VolumeGeometry& g = f.geometry;
  std::mt19937 rng(seed);
  Accuracy acc;
  int attempts = 0;
  while (acc.sampled < samples && attempts++ < samples * 50) {
    const int i = static_cast<int>(rng() % static_cast<unsigned>(hf.nx));
    const int j = static_cast<int>(rng() % static_cast<unsigned>(hf.ny));
    const int k = static_cast<int>(rng() % static_cast<unsigned>(g.nz));
    const double z = g.z_of(k);
    if (z < hf.at(i, j) + g.dz_m) continue;
    const double below = exact_visibility(hf, area, p, i, j, z - g.dz_m);
    const double here = exact_visibility(hf, area, p, i, j, z);
    const double above = exact_visibility(hf, area, p, i, j, z + g.dz_m);
    const double lo = std::min({below, here, above}) - 0.005;
    const double hi = std::max({below, here, above}) + 0.005;
    const double v = f.at(i, j, k);
    ++acc.sampled;
    if (v >= lo && v <= hi) ++acc.within;
  }
  return acc;
}

FieldParams small_params(RangeShape shape, int range_posts, int nz = 48) {
  FieldParams p;
  p.nz = nz;
  p.ceiling_m = 150;
  p.range_shape = shape;
  p.range_posts = range_posts;
  return p;
}

void expect_accurate(const Heightfield& hf, const FieldParams& p, int samples = 250) {
  const DenseVolume f = build(hf, p);
  const Accuracy acc = check_against_exact(hf, p, f, samples, 7);
  EXPECT_GE(acc.sampled, samples / 2);
  EXPECT_GE(acc.fraction(), 0.99) << acc.within << " of " << acc.sampled << " voxels within";
}

// -- properties ---------------------------------------------------------------

TEST(VisibilityField, ValuesStayInZeroOne) {
  for (RangeShape shape : {RangeShape::none, RangeShape::cube, RangeShape::sphere}) {
    const Heightfield hf = fractal(40, 3);
    const DenseVolume f = build(hf, small_params(shape, 12));
    for (float v : f.values) {
      ASSERT_GE(v, 0.0f);
      ASSERT_LE(v, 1.0f);
    }
  }
}

TEST(VisibilityField, NonDecreasingUpwardWithoutRange) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const Heightfield hf = fractal(36, seed);
    const DenseVolume f = build(hf, small_params(RangeShape::none, 0));
    const VolumeGeometry& g = f.geometry;
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i)
        for (int k = 1; k < g.nz; ++k) ASSERT_GE(f.at(i, j, k), f.at(i, j, k - 1)) << i << "," << j << "," << k;
  }
}

TEST(VisibilityField, FlatTerrainWithoutRangeSeesEverything) {
  const Heightfield hf = flat(24);
  const DenseVolume f = build(hf, small_params(RangeShape::none, 0));
  for (float v : f.values) ASSERT_NEAR(v, 1.0f, 1e-5f);
}

TEST(VisibilityField, FlatTerrainCubeCountsPostsInTheSquare) {
  // Every post within the Chebyshev square sees every voxel of the cube's
  // height: F = (clipped square's post count) / (all posts).
  const int n = 30, r = 5;
  const Heightfield hf = flat(n, 10.0);
  FieldParams p = small_params(RangeShape::cube, r, 40);
  p.ceiling_m = 2.0 * r * 10.0 * 1.5;  // the grid reaches above the cube's top
  const DenseVolume f = build(hf, p);
  const VolumeGeometry& g = f.geometry;
  for (int j = 0; j < n; j += 3) {
    for (int i = 0; i < n; i += 2) {
      const int cx = std::min(n - 1, i + r) - std::max(0, i - r) + 1;
      const int cy = std::min(n - 1, j + r) - std::max(0, j - r) + 1;
      for (int k = 0; k < g.nz; ++k) {
        const bool in_cube = g.z_of(k) <= 100.0 + 2.0 * r * 10.0 + 1e-9;
        const double expected = in_cube ? double(cx * cy) / (n * n) : 0.0;
        ASSERT_NEAR(f.at(i, j, k), expected, 1e-5) << i << "," << j << "," << k;
      }
    }
  }
}

TEST(VisibilityField, ZeroWeightsGiveZero) {
  const Heightfield hf = fractal(32, 5);
  FieldParams p = small_params(RangeShape::cube, 8);
  p.weights.assign(hf.size(), 0.0f);
  for (float v : build(hf, p).values) ASSERT_EQ(v, 0.0f);
}

TEST(VisibilityField, WeightsSelectObservers) {
  // Observers only in the western half: F_p matches the exact sum over them.
  const Heightfield hf = fractal(40, 9);
  FieldParams p = small_params(RangeShape::cube, 10);
  p.weights.assign(hf.size(), 0.0f);
  for (int j = 0; j < hf.ny; ++j)
    for (int i = 0; i < hf.nx / 2; ++i) p.weights[static_cast<std::size_t>(j * hf.nx + i)] = 0.7f;
  const DenseVolume f = build(hf, p);
  EXPECT_GE(check_against_exact(hf, p, f, 150, 3).fraction(), 0.99);
  // Far east, beyond every observer's cube, nothing is seen.
  for (int k = 0; k < f.geometry.nz; ++k) EXPECT_EQ(f.at(hf.nx - 1, 5, k), 0.0f);
}

TEST(VisibilityField, IdenticalWhateverTheThreadCount) {
  const Heightfield hf = fractal(50, 11);
  FieldParams p = small_params(RangeShape::cube, 14);
  p.threads = 1;
  const DenseVolume one = build(hf, p);
  for (int threads : {2, 3, 5}) {
    p.threads = threads;
    const DenseVolume many = build(hf, p);
    ASSERT_EQ(one.values.size(), many.values.size());
    EXPECT_EQ(0, std::memcmp(one.values.data(), many.values.data(), one.values.size() * sizeof(float)))
        << threads << " threads";
  }
}

// Rows handed to a sink, by row, in the order they came.
class RowCollector final : public VolumeRowSink {
 public:
  explicit RowCollector(const VolumeGeometry& g) : g_(g) {}
  Status write_row(int j, const float* values) override {
    order.push_back(j);
    rows[j].assign(values, values + static_cast<std::size_t>(g_.nz) * static_cast<std::size_t>(g_.nx));
    return Status::ok_status();
  }
  std::vector<int> order;
  std::map<int, std::vector<float>> rows;

 private:
  VolumeGeometry g_;
};

// What one of several processes builds (an MPI rank's band of rows) is the
// whole build's rows, byte for byte, whatever the band and the range shape.
TEST(VisibilityField, ABandOfRowsIsTheWholeBuildsRows) {
  const Heightfield hf = fractal(41, 5);
  for (const RangeShape shape : {RangeShape::cube, RangeShape::sphere, RangeShape::none}) {
    const FieldParams p = small_params(shape, 6, 24);
    const DenseVolume whole = build(hf, p);
    const VolumeGeometry& g = whole.geometry;
    for (const RowBand band : {RowBand{0, 41}, RowBand{0, 9}, RowBand{9, 10}, RowBand{10, 29}, RowBand{29, 41}}) {
      RowCollector sink(g);
      ASSERT_TRUE(build_visibility_rows(hf, p, band, sink).ok());
      ASSERT_EQ(sink.order.size(), static_cast<std::size_t>(band.end - band.first)) << to_string(shape);
      for (int j = band.first; j < band.end; ++j) {
        ASSERT_EQ(sink.order[static_cast<std::size_t>(j - band.first)], j);
        const std::vector<float>& row = sink.rows[j];
        for (int k = 0; k < g.nz; ++k) {
          ASSERT_EQ(0, std::memcmp(&row[static_cast<std::size_t>(k) * static_cast<std::size_t>(g.nx)],
                                   &whole.values[g.index(0, j, k)], static_cast<std::size_t>(g.nx) * sizeof(float)))
              << to_string(shape) << " row " << j << " level " << k << " of band " << band.first << ".." << band.end;
        }
      }
    }
  }
  RowCollector sink(volume_geometry(hf, small_params(RangeShape::cube, 6)));
  for (const RowBand bad : {RowBand{-1, 5}, RowBand{5, 5}, RowBand{30, 42}}) {
    EXPECT_FALSE(build_visibility_rows(hf, small_params(RangeShape::cube, 6), bad, sink).ok());
  }
  EXPECT_TRUE(sink.order.empty());
}

// The parameters with a memory limit that leaves the builder `batch` observer
// rows at a time (the limit it takes for a field far larger than memory).
FieldParams with_batch_rows(FieldParams p, const Heightfield& hf, int batch) {
  double lo = 0, hi = 1024;  // MiB; the batch grows with the limit
  for (int it = 0; it < 60; ++it) {
    p.max_memory_mib = 0.5 * (lo + hi);
    const Result<BuildPlan> plan = plan_visibility_build(hf, p);
    (plan.ok() && plan->batch_rows >= batch ? hi : lo) = p.max_memory_mib;
  }
  p.max_memory_mib = hi;
  return p;
}

// A memory limit that leaves one or two observer rows a batch: the rows
// leave the window as soon as no later observer reaches them, band or not.
TEST(VisibilityField, BandsBuiltInBatchesOfOneOrTwoRowsAreTheWholeBuildsRows) {
  const Heightfield hf = fractal(41, 7);
  const FieldParams p = small_params(RangeShape::cube, 6, 24);
  const DenseVolume whole = build(hf, p);
  const VolumeGeometry& g = whole.geometry;
  for (const int batch : {1, 2}) {
    const FieldParams tight = with_batch_rows(p, hf, batch);
    const Result<BuildPlan> plan = plan_visibility_build(hf, tight);
    ASSERT_TRUE(plan.ok());
    ASSERT_EQ(plan->batch_rows, batch);
    for (const RowBand band : {RowBand{0, 41}, RowBand{0, 16}, RowBand{16, 32}, RowBand{32, 41}, RowBand{13, 14}}) {
      RowCollector sink(g);
      ASSERT_TRUE(build_visibility_rows(hf, tight, band, sink).ok());
      ASSERT_EQ(sink.order.size(), static_cast<std::size_t>(band.end - band.first));
      for (int j = band.first; j < band.end; ++j) {
        ASSERT_EQ(sink.order[static_cast<std::size_t>(j - band.first)], j);
        for (int k = 0; k < g.nz; ++k) {
          ASSERT_EQ(0, std::memcmp(&sink.rows[j][static_cast<std::size_t>(k) * static_cast<std::size_t>(g.nx)],
                                   &whole.values[g.index(0, j, k)], static_cast<std::size_t>(g.nx) * sizeof(float)))
              << "batch " << batch << " row " << j << " level " << k << " of band " << band.first << ".." << band.end;
        }
      }
    }
  }
}

// The shares of a build split by observers, each in its own thread as
// processes would run, through one mailbox: what each share wrote, its
// figures and its status.
struct SplitRun {
  std::vector<RowCollector> sinks;
  std::vector<BuildStats> stats;
  std::vector<Status> status;
  std::uint64_t rows_sent = 0;
};

SplitRun run_split(const Heightfield& hf, const FieldParams& p, const std::vector<RowBand>& bands) {
  const std::size_t n = bands.size();
  SplitRun run{std::vector<RowCollector>(n, RowCollector(volume_geometry(hf, p))), std::vector<BuildStats>(n),
               std::vector<Status>(n, Status::ok_status()), 0};
  test::LocalRowMail mail(static_cast<int>(n));
  std::vector<std::thread> shares;
  for (std::size_t q = 0; q < n; ++q) {
    shares.emplace_back([&, q] {
      run.status[q] = build_visibility_share(hf, p, bands, static_cast<int>(q), mail.share(static_cast<int>(q)),
                                             run.sinks[q], {}, &run.stats[q]);
    });
  }
  for (std::thread& t : shares) t.join();
  run.rows_sent = mail.rows_sent();
  return run;
}

// Split by observers (each hull computed once, the sums over rows another
// share owns sent to it): every row is the whole build's, byte for byte,
// written once by its owner, for narrow, wide and empty bands, every range
// shape, and batches of one observer row; the shares together compute each
// observer row's hulls once and evaluate each (observer, target) pair once,
// as the whole build does.
TEST(VisibilityField, ABuildSplitByObserversIsTheWholeBuildsRows) {
  const Heightfield hf = fractal(41, 5);
  const std::vector<std::vector<RowBand>> splits = {
      {{0, 20}, {20, 41}},
      {{0, 9}, {9, 10}, {10, 29}, {29, 29}, {29, 41}},  // a band narrower than the range, an empty one
      {{0, 3}, {3, 6}, {6, 9}, {9, 12}, {12, 41}},      // rows reached by several shares' observers
  };
  for (const RangeShape shape : {RangeShape::cube, RangeShape::sphere, RangeShape::none}) {
    for (const int batch : {0, 1}) {
      const FieldParams wide = small_params(shape, 6, 24);
      const FieldParams p = batch ? with_batch_rows(wide, hf, batch) : wide;
      BuildStats whole_stats;
      Result<DenseVolume> whole = build_visibility_dense(hf, wide, {}, &whole_stats);
      ASSERT_TRUE(whole.ok()) << whole.status().message();
      const VolumeGeometry& g = whole->geometry;
      for (const std::vector<RowBand>& bands : splits) {
        SplitRun run = run_split(hf, p, bands);
        std::uint64_t cells = 0;
        int observer_rows = 0;
        for (std::size_t q = 0; q < bands.size(); ++q) {
          ASSERT_TRUE(run.status[q].ok()) << run.status[q].message();
          cells += run.stats[q].hull_cells;
          observer_rows += run.stats[q].observer_rows;
          const RowCollector& sink = run.sinks[q];
          ASSERT_EQ(sink.order.size(), static_cast<std::size_t>(bands[q].end - bands[q].first))
              << to_string(shape) << " share " << q;
          for (int j = bands[q].first; j < bands[q].end; ++j) {
            ASSERT_EQ(sink.rows.count(j), 1u) << "share " << q << " row " << j;
            for (int k = 0; k < g.nz; ++k) {
              ASSERT_EQ(0,
                        std::memcmp(&sink.rows.at(j)[static_cast<std::size_t>(k) * static_cast<std::size_t>(g.nx)],
                                    &whole->values[g.index(0, j, k)], static_cast<std::size_t>(g.nx) * sizeof(float)))
                  << to_string(shape) << " batch " << batch << " share " << q << " row " << j << " level " << k;
            }
          }
        }
        EXPECT_EQ(observer_rows, hf.ny) << to_string(shape);  // each observer's hull once
        EXPECT_EQ(cells, whole_stats.hull_cells) << to_string(shape);
        EXPECT_GT(run.rows_sent, 0u);
      }
    }
  }
}

TEST(VisibilityField, ASplitThatDoesNotCoverTheGridIsRefused) {
  const Heightfield hf = fractal(20, 3);
  const FieldParams p = small_params(RangeShape::cube, 4, 16);
  test::LocalRowMail mail(3);
  RowCollector sink(volume_geometry(hf, p));
  for (const std::vector<RowBand>& bands : std::vector<std::vector<RowBand>>{
           {}, {{0, 10}}, {{0, 10}, {11, 20}}, {{0, 20}, {19, 20}}, {{0, 12}, {12, 10}, {10, 20}}}) {
    const Status st = build_visibility_share(hf, p, bands, 0, mail.share(0), sink);
    ASSERT_FALSE(st.ok()) << bands.size() << " bands";
    EXPECT_NE(st.message().find("do not cover the grid's 20 rows"), std::string::npos) << st.message();
  }
  const Status st = build_visibility_share(hf, p, {{0, 10}, {10, 20}}, 2, mail.share(0), sink);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("share 2 is not one of the split's 2"), std::string::npos) << st.message();
  EXPECT_TRUE(sink.order.empty());
  EXPECT_EQ(mail.rows_sent(), 0u);
}

TEST(VisibilityField, BelowTheTerrainIsZero) {
  const Heightfield hf = fractal(32, 4);
  const DenseVolume f = build(hf, small_params(RangeShape::cube, 8));
  const VolumeGeometry& g = f.geometry;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      for (int k = 0; k < g.nz && g.z_of(k) < hf.at(i, j); ++k) ASSERT_EQ(f.at(i, j, k), 0.0f);
}

TEST(VisibilityField, SightLinesAreSymmetric) {
  const Heightfield hf = fractal(40, 21);
  std::mt19937 rng(5);
  for (int n = 0; n < 2000; ++n) {
    const int ai = static_cast<int>(rng() % 40u), aj = static_cast<int>(rng() % 40u);
    const int bi = static_cast<int>(rng() % 40u), bj = static_cast<int>(rng() % 40u);
    const double az = hf.at(ai, aj) + 2.0 + static_cast<double>(rng() % 50u),
                 bz = hf.at(bi, bj) + static_cast<double>(rng() % 80u);
    ASSERT_EQ(r3_visible(hf, ai, aj, az, bi, bj, bz, 0.0), r3_visible(hf, bi, bj, bz, ai, aj, az, 0.0));
  }
}

// The two-phase scatter against a plain sum over observers of the scalar
// horizon: same recursion, so any indexing slip shows.
void expect_matches_per_observer_hulls(const Heightfield& hf, const FieldParams& p) {
  const DenseVolume f = build(hf, p);
  const VolumeGeometry& g = f.geometry;
  const int r = hull_radius_posts(p, hf);
  const PaddedTerrain t = pad_terrain(hf, g, r);
  const ObserverWeights ow = observer_weights(hf, area_factor(hf), p.weights);
  std::vector<double> ref(g.voxel_count(), 0.0);
  std::vector<float> horizon;
  const int side = 2 * r + 1;
  const double range_m = p.range_posts * hf.spacing_m;
  for (int pj = 0; pj < hf.ny; ++pj) {
    for (int pi = 0; pi < hf.nx; ++pi) {
      const double ground = hf.at(pi, pj), eye = ground + p.eye_height_m;
      observer_horizon(t, r, p.exact_rings, hf.spacing_m, p.curvature_coeff, pi, pj, eye, horizon);
      const double w = ow.weight[static_cast<std::size_t>(pj * hf.nx + pi)];
      for (int j = std::max(0, pj - r); j <= std::min(hf.ny - 1, pj + r); ++j) {
        for (int i = std::max(0, pi - r); i <= std::min(hf.nx - 1, pi + r); ++i) {
          const double h = horizon[static_cast<std::size_t>((j - pj + r) * side + i - pi + r)];
          const double d = std::hypot(double(i - pi), double(j - pj)) * hf.spacing_m;
          const double drop = p.curvature_coeff * d * d / (2.0 * kEarthRadiusM);
          const double hull = h <= kNoHorizon ? -1e30 : eye + d * h + drop;
          double lo = std::max(hull, -1e29), hi = 1e30;
          bool ground_ok = true;  // z >= terrain handled below
          if (p.range_shape == RangeShape::cube) hi = ground + 2.0 * range_m;
          if (p.range_shape == RangeShape::sphere) {
            if (d > range_m) continue;
            const double span = std::sqrt(range_m * range_m - d * d);
            hi = eye + span;
            lo = std::max(lo, eye - span - 1e-9);
          }
          (void)ground_ok;
          for (int k = 0; k < g.nz; ++k) {
            const double z = g.z_of(k);
            if (z < hf.at(i, j) || z <= lo || z > hi) continue;
            if (p.range_shape == RangeShape::cube && z < ground) continue;
            ref[g.index(i, j, k)] += w;
          }
        }
      }
    }
  }
  const double max_w = *std::max_element(ow.weight.begin(), ow.weight.end());
  std::size_t equal = 0;
  for (std::size_t n = 0; n < ref.size(); ++n) {
    const double expected = ref[n] * ow.norm;
    // Float against double may move a hull across a level boundary rarely.
    ASSERT_NEAR(f.values[n], expected, 4 * max_w * ow.norm + 1e-6) << "voxel " << n;
    equal += std::fabs(f.values[n] - expected) < 1e-6;
  }
  EXPECT_GE(equal, ref.size() - ref.size() / 200);
}

TEST(VisibilityField, ScatterMatchesPerObserverHulls) {
  {
    SCOPED_TRACE("cube");
    expect_matches_per_observer_hulls(fractal(37, 3), small_params(RangeShape::cube, 9));
  }
  {
    SCOPED_TRACE("none");
    expect_matches_per_observer_hulls(fractal(35, 4), small_params(RangeShape::none, 0));
  }
  {
    SCOPED_TRACE("sphere");
    expect_matches_per_observer_hulls(fractal(33, 5), small_params(RangeShape::sphere, 8));
  }
  SCOPED_TRACE("curvature");
  FieldParams curved = small_params(RangeShape::cube, 12);
  curved.curvature_coeff = 0.85714;
  curved.exact_rings = 4;
  expect_matches_per_observer_hulls(fractal(40, 6, 200.0), curved);
}

// -- accuracy against the exact R3 reference ------------------------------------

TEST(VisibilityAccuracy, Flat) { expect_accurate(flat(40), small_params(RangeShape::cube, 12)); }

TEST(VisibilityAccuracy, Wall) {
  expect_accurate(wall(48, 24, 40.0f), small_params(RangeShape::cube, 16));
  expect_accurate(wall(40, 13, 25.0f), small_params(RangeShape::none, 0));
}

TEST(VisibilityAccuracy, TwoPrisms) {
  expect_accurate(two_prisms(64), small_params(RangeShape::cube, 20));
  expect_accurate(two_prisms(40), small_params(RangeShape::none, 0));
}

TEST(VisibilityAccuracy, FractalNoise) {
  for (std::uint32_t seed : {1u, 2u}) expect_accurate(fractal(64, seed), small_params(RangeShape::cube, 20));
  expect_accurate(fractal(40, 8), small_params(RangeShape::none, 0));
  expect_accurate(fractal(48, 6), small_params(RangeShape::sphere, 14));
}

TEST(VisibilityAccuracy, CurvatureAndRefraction) {
  // 30 m posts and a 48-post range: the drop reaches about 100 m at the edge.
  FieldParams p = small_params(RangeShape::cube, 48);
  p.curvature_coeff = 0.85714;
  expect_accurate(fractal(64, 12, 250.0, 200.0), p, 150);
}

// An interior window of a real DEM (its nodata edge is filled on reading, and
// the window stays clear of it).
Heightfield real_crop(const std::string& file, int i0, int j0, int n) {
  Result<Heightfield> hf = read_heightfield(test_data(file), {NodataPolicy::fill});
  EXPECT_TRUE(hf.ok()) << hf.status().message();
  return hf.ok() ? crop(*hf, i0, j0, n, n) : flat(n);
}

TEST(VisibilityAccuracy, RealSanFranciscoNorth) {
  // Twin Peaks side of the quad: city hills and valleys.
  expect_accurate(real_crop("sf_north_utm10_30m.tif", 200, 300, 96), small_params(RangeShape::cube, 24));
}

TEST(VisibilityAccuracy, RealTaunus) {
  expect_accurate(real_crop("taunus_utm32n_90m_512.tif", 200, 160, 96), small_params(RangeShape::cube, 24));
  expect_accurate(real_crop("taunus_utm32n_90m_512.tif", 40, 300, 40), small_params(RangeShape::none, 0));
}

TEST(VisibilityAccuracy, SharedRealDems) {
  // The other real DEMs of ../shared/data that are already in metres.
  const std::string shared = VISVOL_SHARED_DATA;
  int checked = 0;
  for (const char* name :
       {"/dem/whitebox_dem.tif", "/dem/grass_viewshed_reference/elevation.ascii", "/dem/sf_north_usgs24k.dem"}) {
    Result<Heightfield> hf = read_heightfield(shared + name, {NodataPolicy::fill});
    if (!hf.ok() && hf.status().code() == Errc::io) continue;  // shared data absent
    ASSERT_TRUE(hf.ok()) << hf.status().message();
    const int n = std::min({hf->nx - 20, hf->ny - 20, 80});
    expect_accurate(crop(*hf, 10, 10, n, n), small_params(RangeShape::cube, 20), 150);
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "shared/data not found at " << shared;
}

// -- bad input ---------------------------------------------------------------------

TEST(VisibilityFieldInput, RejectsNaNPost) {
  Heightfield hf = flat(16);
  hf.at(3, 4) = std::numeric_limits<float>::quiet_NaN();
  const Result<DenseVolume> v = build_visibility_dense(hf, small_params(RangeShape::cube, 4));
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.status().message().find("(3, 4)"), std::string::npos);
}

TEST(VisibilityFieldInput, RejectsDegenerateGridsAndSpacing) {
  EXPECT_FALSE(build_visibility_dense(blank(1, 1, 10.0), small_params(RangeShape::cube, 4)).ok());
  Heightfield hf = flat(8);
  hf.spacing_m = 0;
  EXPECT_FALSE(build_visibility_dense(hf, small_params(RangeShape::cube, 4)).ok());
  hf.spacing_m = -5;
  EXPECT_FALSE(build_visibility_dense(hf, small_params(RangeShape::cube, 4)).ok());
}

TEST(VisibilityFieldInput, RejectsBadParameters) {
  const Heightfield hf = flat(8);
  FieldParams p = small_params(RangeShape::cube, 4);
  p.nz = 1;
  EXPECT_NE(build_visibility_dense(hf, p).status().message().find("levels"), std::string::npos);
  p = small_params(RangeShape::cube, 0);
  EXPECT_NE(build_visibility_dense(hf, p).status().message().find("range"), std::string::npos);
  p = small_params(RangeShape::cube, 4);
  p.eye_height_m = std::nan("");
  EXPECT_FALSE(build_visibility_dense(hf, p).ok());
  p = small_params(RangeShape::cube, 4);
  p.weights.assign(hf.size(), 1.5f);
  EXPECT_NE(build_visibility_dense(hf, p).status().message().find("[0, 1]"), std::string::npos);
}

TEST(VisibilityFieldInput, AMemoryLimitTooLargeForBytesIsRefusedAndTheLargestWorks) {
  // 1e308 MiB in bytes overflowed a size_t: a 2 MiB build was refused as over 0 bytes.
  const Heightfield hf = flat(8);
  FieldParams p = small_params(RangeShape::cube, 4);
  p.max_memory_mib = 1e308;
  const Result<DenseVolume> v = build_visibility_dense(hf, p);
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), Errc::invalid_argument);
  EXPECT_NE(v.status().message().find("memory limit: 1e+308 MiB is outside 0..16777216 MiB"), std::string::npos)
      << v.status().message();
  p.max_memory_mib = kMaxMemoryMib;
  EXPECT_TRUE(build_visibility_dense(hf, p).ok());
  p.max_memory_mib = 0;
  EXPECT_FALSE(build_visibility_dense(hf, p).ok());
}

TEST(VisibilityFieldInput, RefusesAbsurdSizesWithTheNeededMemory) {
  // 6000 x 6000 x 255 voxels (36 GB) in memory is far beyond the limit.
  Heightfield hf;
  hf.nx = 6000;
  hf.ny = 6000;
  hf.spacing_m = 10;
  hf.height_m.assign(hf.size(), 0.0f);
  FieldParams p = small_params(RangeShape::cube, 64, 255);
  p.max_memory_mib = 4096;
  const Result<DenseVolume> v = build_visibility_dense(hf, p);
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), Errc::resource);
  EXPECT_NE(v.status().message().find("MiB"), std::string::npos);
  // the streamed build's plan names its need and the limit as given
  p.max_memory_mib = 100;
  const Result<BuildPlan> plan = plan_visibility_build(hf, p);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.status().message().find(" MiB of working memory (hull levels "), std::string::npos)
      << plan.status().message();
  EXPECT_NE(plan.status().message().find("the limit is 100 MiB: "), std::string::npos) << plan.status().message();
  // a limit under a MiB, and a need as small: to the hundredth, not "0"
  const Heightfield small = flat(40, 10.0);
  FieldParams q = small_params(RangeShape::cube, 8);
  q.max_memory_mib = 0.001;
  const Result<BuildPlan> tiny = plan_visibility_build(small, q);
  ASSERT_FALSE(tiny.ok());
  const std::string& said = tiny.status().message();
  const std::size_t at = said.find(" needs ");
  ASSERT_NE(at, std::string::npos) << said;
  EXPECT_GT(std::stod(said.substr(at + 7)), 0.0) << said;  // "needs 0.02 MiB", not "needs 0 MiB"
  EXPECT_NE(said.find(" MiB of working memory"), std::string::npos) << said;
  EXPECT_NE(tiny.status().message().find("the limit is 0.001 MiB"), std::string::npos) << tiny.status().message();
}

TEST(VisibilityFieldInput, PlanRefusesRangeNoneOnLargeGrids) {
  Heightfield hf = flat(4000, 10.0);
  FieldParams p = small_params(RangeShape::none, 0, 128);
  p.max_memory_mib = 2048;
  const Result<BuildPlan> plan = plan_visibility_build(hf, p);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.status().message().find("smaller range"), std::string::npos);
}

TEST(VisibilityFieldStats, CountsHullCells) {
  const Heightfield hf = flat(20);
  BuildStats stats;
  ASSERT_TRUE(build_visibility_dense(hf, small_params(RangeShape::none, 0), {}, &stats).ok());
  // Range none: every observer evaluates every target column.
  EXPECT_EQ(stats.hull_cells, 20ull * 20 * 20 * 20);
  EXPECT_GT(stats.wall_s, 0.0);
}

}  // namespace
}  // namespace visvol::fields
