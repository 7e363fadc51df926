// PointGrid against brute force: its nearest point is the exact nearest (distance equal to the
// last bit), its cells along a segment hold every point within the radius, on a dense surface
// (the occupancy-bit index), on clusters far apart (the hash index) and for queries far from
// every point (the kd-tree over cell centres). M3C2 and C2C give the same results from grids
// as from kd-trees, and voxelize() the same moments as a std::sort of (key, index) pairs.
#include "worker/compare/point_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "tests/worker/compare/test_surfaces.h"
#include "worker/compare/c2c_distance.h"
#include "worker/compare/m3c2.h"
#include "worker/compare/voxel_moments.h"

namespace keel::compare {
namespace {

using testing::sample_box;
using testing::sample_rectangle;
using testing::sample_sphere;

double brute_nearest(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& q) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : points) best = std::min(best, (p.cast<double>() - q.cast<double>()).norm());
  return best;
}

// A box's faces, a sphere and a tilted plane, ~2 cm apart like a voxel-filtered map.
std::vector<Eigen::Vector3f> dense_surfaces(std::mt19937& rng) {
  std::vector<Eigen::Vector3f> out;
  sample_box({0, 0, 0}, {2, 1.5, 1}, 2500, 0.005, rng, &out);
  sample_sphere({3.5, 0.5, 0.5}, 0.6, 2500, 0.005, rng, &out);
  sample_rectangle({-1, -1, -0.5}, Eigen::Vector3d(1, 0, 0.3).normalized(), 5,
                   Eigen::Vector3d(0, 1, 0), 3, 2500, 0.003, rng, &out);
  return out;
}

// Queries near the surfaces (most C2C queries), a few metres off, and on indexed points.
std::vector<Eigen::Vector3f> queries_around(const std::vector<Eigen::Vector3f>& points,
                                            size_t count, std::mt19937& rng) {
  std::normal_distribution<float> near(0.0f, 0.03f), far(0.0f, 2.0f);
  std::uniform_int_distribution<size_t> pick(0, points.size() - 1);
  std::vector<Eigen::Vector3f> out;
  for (size_t i = 0; i < count; ++i) {
    const Eigen::Vector3f& p = points[pick(rng)];
    if (i % 10 == 0)
      out.push_back(p);
    else if (i % 10 == 1)
      out.push_back(p + Eigen::Vector3f(far(rng), far(rng), far(rng)));
    else
      out.push_back(p + Eigen::Vector3f(near(rng), near(rng), near(rng)));
  }
  out.push_back({40.0f, -30.0f, 12.0f});  // far from everything
  return out;
}

void expect_nearest_exact(const std::vector<Eigen::Vector3f>& points, double cell_m,
                          const std::vector<Eigen::Vector3f>& queries) {
  const PointGrid grid(points, cell_m, 2);
  for (size_t i = 0; i < queries.size(); ++i) {
    const Neighbour nb = grid.nearest(queries[i]);
    ASSERT_EQ(nb.distance_m, brute_nearest(points, queries[i])) << "query " << i;
    ASSERT_EQ(nb.distance_m, (points[nb.index].cast<double>() - queries[i].cast<double>()).norm());
  }
}

TEST(PointGrid, NearestIsExactOnADenseSurface) {
  std::mt19937 rng(11);
  const std::vector<Eigen::Vector3f> points = dense_surfaces(rng);
  const std::vector<Eigen::Vector3f> queries = queries_around(points, 3000, rng);
  for (double cell : {0.1, 0.05, 0.37}) expect_nearest_exact(points, cell, queries);
}

TEST(PointGrid, NearestIsExactOnClustersFarApart) {
  // Two clusters 2 km apart in 5 cm cells: the box would hold ~10^13 cells, so the grid
  // indexes its cells in a hash table.
  std::mt19937 rng(12);
  std::vector<Eigen::Vector3f> points;
  sample_sphere({0, 0, 0}, 0.5, 3000, 0.002, rng, &points);
  sample_sphere({2000, 1500, 30}, 0.5, 3000, 0.002, rng, &points);
  std::vector<Eigen::Vector3f> queries = queries_around(points, 2000, rng);
  queries.push_back({1000, 750, 15});  // midway
  expect_nearest_exact(points, 0.05, queries);
}

// Random segments from `start` (up to 1 m long): every point within the radius must be in the
// runs near_segment returns.
void expect_segments_complete(const std::vector<Eigen::Vector3f>& points, double cell_m,
                              const Eigen::Vector3d& start, const Eigen::Vector3d& spread,
                              std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const PointGrid grid(points, cell_m);
  std::vector<PointGrid::Run> runs;
  for (int s = 0; s < 300; ++s) {
    const Eigen::Vector3d from =
        start + spread.cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    const Eigen::Vector3d to = from + unit(rng) * Eigen::Vector3d::Random().normalized();
    const double radius = s % 2 ? 0.1 : 0.03;
    grid.near_segment(from, to, radius, &runs);
    std::set<uint32_t> found;
    for (const auto& run : runs)
      for (uint32_t e = run.begin; e < run.end; ++e) found.insert(grid.input_index()[e]);
    const Eigen::Vector3d axis = to - from;
    for (uint32_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d v = points[i].cast<double>() - from;
      const double t = std::clamp(v.dot(axis) / std::max(axis.squaredNorm(), 1e-300), 0.0, 1.0);
      if ((v - t * axis).norm() <= radius)
        ASSERT_TRUE(found.count(i)) << "segment " << s << " misses point " << i;
    }
  }
}

TEST(PointGrid, CellsAlongASegmentHoldEveryPointWithinTheRadius) {
  std::mt19937 rng(13);
  const std::vector<Eigen::Vector3f> points = dense_surfaces(rng);
  for (double cell : {0.1, 0.06})
    expect_segments_complete(points, cell, {-1, -1, -0.5}, {5, 3, 2}, rng);
  // Far-apart clusters: the hash index.
  std::vector<Eigen::Vector3f> clusters;
  sample_sphere({0, 0, 0}, 0.5, 3000, 0.002, rng, &clusters);
  sample_sphere({2000, 1500, 30}, 0.5, 3000, 0.002, rng, &clusters);
  expect_segments_complete(clusters, 0.05, {-0.7, -0.7, -0.7}, {1.4, 1.4, 1.4}, rng);
  expect_segments_complete(clusters, 0.05, {1999.3, 1499.3, 29.3}, {1.4, 1.4, 1.4}, rng);
}

TEST(PointGrid, C2cFromGridsEqualsBruteForce) {
  std::mt19937 rng(14);
  const std::vector<Eigen::Vector3f> reference = dense_surfaces(rng);
  const std::vector<Eigen::Vector3f> compared = queries_around(reference, 4000, rng);
  const PointGrid grid_a(reference, 0.1), grid_b(compared, 0.1);
  const std::vector<float> d = c2c_distances(grid_a, grid_b, 2);
  ASSERT_EQ(d.size(), compared.size());
  for (size_t i = 0; i < compared.size(); ++i)
    ASSERT_EQ(d[i], float(brute_nearest(reference, compared[i]))) << "point " << i;
}

TEST(PointGrid, M3c2FromGridsEqualsM3c2FromKdTrees) {
  std::mt19937 rng(15);
  std::vector<Eigen::Vector3f> a = dense_surfaces(rng), b;
  for (const auto& p : a) b.push_back(p + Eigen::Vector3f(0.0f, 0.0f, 0.01f));
  sample_box({0.5, 0.2, 1.0}, {0.9, 0.6, 1.3}, 2500, 0.003, rng, &b);  // new structure on top
  M3c2Options options;
  const NearestIndex ia(a), ib(b);
  const PointGrid ga(a, 0.1), gb(b, 0.1);
  const VoxelMoments va = voxelize(a, 0.125), vb = voxelize(b, 0.125), cores = voxelize(b, 0.1);
  const std::vector<Eigen::Vector3f> views = {{1, -5, 3}, {1, 6, 3}};
  const auto trees = m3c2({&ia, &ib, &va, &vb}, cores.means, views, options);
  const auto grids = m3c2({nullptr, nullptr, &va, &vb, &ga, &gb}, cores.means, views, options);
  ASSERT_EQ(trees.size(), grids.size());
  size_t defined = 0;
  for (size_t i = 0; i < trees.size(); ++i) {
    ASSERT_EQ(trees[i].defined(), grids[i].defined()) << "core " << i;
    ASSERT_EQ(trees[i].count_a, grids[i].count_a) << "core " << i;
    ASSERT_EQ(trees[i].count_b, grids[i].count_b) << "core " << i;
    if (!trees[i].defined()) continue;
    ++defined;
    // The same points, summed in another order: equal but for the last bits.
    EXPECT_NEAR(trees[i].distance_m, grids[i].distance_m, 1e-6f) << "core " << i;
    EXPECT_NEAR(trees[i].lod95_m, grids[i].lod95_m, 1e-6f) << "core " << i;
  }
  EXPECT_GT(defined, trees.size() / 2);
}

// voxelize() as it was written first: std::sort of (key, index) pairs, 21 bits per axis.
VoxelMoments voxelize_by_sort(const std::vector<Eigen::Vector3f>& points, double voxel_m) {
  VoxelMoments out;
  Eigen::Vector3d lo = points.front().cast<double>();
  for (const auto& p : points) lo = lo.cwiseMin(p.cast<double>());
  std::vector<std::pair<uint64_t, uint32_t>> keyed(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d c = (points[i].cast<double>() - lo) / voxel_m;
    keyed[i] = {uint64_t(std::floor(c.x())) << 42 | uint64_t(std::floor(c.y())) << 21 |
                    uint64_t(std::floor(c.z())),
                uint32_t(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  out.voxel_of.resize(points.size());
  for (size_t begin = 0; begin < keyed.size();) {
    size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (; end < keyed.size() && keyed[end].first == keyed[begin].first; ++end)
      sum += points[keyed[end].second].cast<double>();
    Moments m;
    m.count = double(end - begin);
    m.mean = sum / m.count;
    for (size_t k = begin; k < end; ++k) {
      const Eigen::Vector3d d = points[keyed[k].second].cast<double>() - m.mean;
      m.scatter += d * d.transpose();
      out.voxel_of[keyed[k].second] = uint32_t(out.voxels.size());
    }
    out.voxels.push_back(m);
    begin = end;
  }
  return out;
}

TEST(Voxelize, EqualsTheSortOfKeyIndexPairsOnAnyNumberOfThreads) {
  std::mt19937 rng(16);
  const std::vector<Eigen::Vector3f> points = dense_surfaces(rng);
  for (double voxel : {0.1, 0.125, 0.3}) {
    const VoxelMoments expected = voxelize_by_sort(points, voxel);
    for (int threads : {1, 2, 3}) {
      const VoxelMoments got = voxelize(points, voxel, true, threads);
      ASSERT_EQ(got.voxels.size(), expected.voxels.size());
      ASSERT_EQ(got.voxel_of, expected.voxel_of);
      for (size_t v = 0; v < got.voxels.size(); ++v) {
        ASSERT_EQ(got.voxels[v].count, expected.voxels[v].count);
        ASSERT_EQ(got.voxels[v].mean, expected.voxels[v].mean);
        ASSERT_EQ(got.voxels[v].scatter, expected.voxels[v].scatter);
      }
    }
  }
}

TEST(PointGrid, RefusesBadInput) {
  EXPECT_THROW(PointGrid({}, 0.1), std::invalid_argument);
  EXPECT_THROW(PointGrid({{0, 0, 0}}, 0.0), std::invalid_argument);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(PointGrid({{0, 0, 0}, {nan, 0, 0}}, 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace keel::compare
