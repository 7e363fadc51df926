// VoxelAccumulator: the plain streaming voxel grid and the merge rule against brute-force
// oracles, and the saturation the merge rule is for (a densely resampled noisy plane).
#include "worker/mapping/voxel_accumulator.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "tests/worker/mapping/test_clouds.h"

namespace keel::mapping {
namespace {

using testing::random_cloud;

// The rule written out naively: a list of voxels in opening order, every lookup a linear scan,
// sums in double.
struct OracleVoxel {
  std::array<int64_t, 3> key;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;
  Eigen::Vector3d centroid() const { return sum / count; }
};

struct Oracle {
  std::vector<OracleVoxel> voxels;
  size_t merged = 0;
};

Oracle brute_force(const PointCloud& cloud, double leaf_m, double merge_radius_m) {
  Oracle out;
  const int reach = static_cast<int>(std::ceil(merge_radius_m / leaf_m - 1e-9));
  for (const Eigen::Vector3f& pf : cloud.xyz) {
    const Eigen::Vector3d p = pf.cast<double>();
    const std::array<int64_t, 3> key = {static_cast<int64_t>(std::floor(pf.x() / leaf_m)),
                                        static_cast<int64_t>(std::floor(pf.y() / leaf_m)),
                                        static_cast<int64_t>(std::floor(pf.z() / leaf_m))};
    OracleVoxel* target = nullptr;
    for (OracleVoxel& v : out.voxels)
      if (v.key == key) target = &v;
    if (!target && merge_radius_m > 0.0) {
      double best = std::numeric_limits<double>::infinity();
      for (OracleVoxel& v : out.voxels) {
        bool near = true;
        for (int a = 0; a < 3; ++a) near = near && std::llabs(v.key[a] - key[a]) <= reach;
        const double d = (v.centroid() - p).norm();
        if (near && d <= merge_radius_m && d < best) {
          best = d;
          target = &v;
        }
      }
      if (target) ++out.merged;
    }
    if (!target) {
      out.voxels.push_back(OracleVoxel{key});
      target = &out.voxels.back();
    }
    target->sum += p;
    target->count += 1.0;
  }
  return out;
}

void expect_matches(const PointCloud& map, const Oracle& oracle, double tolerance_m) {
  ASSERT_EQ(map.size(), oracle.voxels.size());
  for (size_t n = 0; n < map.size(); ++n) {
    EXPECT_LT((map.xyz[n].cast<double>() - oracle.voxels[n].centroid()).norm(), tolerance_m)
        << "voxel " << n;
  }
}

TEST(VoxelAccumulator, WithoutMergingEqualsBruteForceVoxelGridInBatches) {
  const PointCloud cloud = random_cloud(4000, -1.f, 1.f, 7);
  VoxelAccumulator grid(0.1);
  PointCloud part;
  for (size_t n = 0; n < cloud.size(); ++n) {
    part.xyz.push_back(cloud.xyz[n]);
    if (part.size() == 333 || n + 1 == cloud.size()) {  // batches that split blocks of 32
      grid.add(part);
      part = PointCloud{};
    }
  }
  const Oracle oracle = brute_force(cloud, 0.1, 0.0);
  expect_matches(grid.centroids(), oracle, 1e-5);
  EXPECT_EQ(grid.points_merged(), 0u);
  EXPECT_EQ(grid.points_added(), cloud.size());
}

TEST(VoxelAccumulator, MergeRuleEqualsBruteForce) {
  // ~4 points per voxel, so points often land in empty voxels next to occupied ones.
  const PointCloud cloud = random_cloud(4000, -0.5f, 0.5f, 11);
  for (const double radius_leaves : {0.3, 1.0, 1.6, 2.0}) {
    SCOPED_TRACE(radius_leaves);
    const double leaf = 0.1;
    VoxelAccumulator merged(leaf, radius_leaves * leaf);
    // Three batches: the rule runs in point order across add() calls.
    for (size_t begin = 0; begin < cloud.size(); begin += 1500) {
      PointCloud part;
      for (size_t n = begin; n < std::min(cloud.size(), begin + 1500); ++n)
        part.xyz.push_back(cloud.xyz[n]);
      merged.add(part);
    }
    const Oracle oracle = brute_force(cloud, leaf, radius_leaves * leaf);
    expect_matches(merged.centroids(), oracle, 1e-5);
    EXPECT_EQ(merged.points_merged(), oracle.merged);
    EXPECT_GT(oracle.merged, 0u);  // the rule did something
    EXPECT_LT(merged.voxel_count(), brute_force(cloud, leaf, 0.0).voxels.size());
  }
}

// A unit square of the plane z = 0 sampled with range noise sigma = 1 cm (the simulated
// lidar's), at a 2 cm leaf. A sparse pass (1.3 points per 2 cm cell of the plane, like the
// 5-minute bridge survey) leaves most voxels of the +-3 sigma noise shell empty, so 6x denser
// sampling fills many more; the merge rule caps the map at about one point per merge-radius
// ball of the shell, so it grows less and the map is smaller at every density.
PointCloud noisy_plane(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::normal_distribution<float> noise(0.f, 0.01f);
  PointCloud cloud;
  for (size_t k = 0; k < n; ++k) cloud.xyz.emplace_back(u(rng), u(rng), noise(rng));
  return cloud;
}

size_t voxels_after(const PointCloud& cloud, double leaf_m, double merge_radius_m) {
  VoxelAccumulator grid(leaf_m, merge_radius_m);
  grid.add(cloud);
  return grid.voxel_count();
}

TEST(VoxelAccumulator, MergingBoundsTheMapOfADenselyResampledPlane) {
  const double leaf = 0.02;
  const PointCloud sparse = noisy_plane(3250, 1);
  const PointCloud dense = noisy_plane(19500, 2);  // 6x
  const double plain_growth =
      double(voxels_after(dense, leaf, 0.0)) / double(voxels_after(sparse, leaf, 0.0));
  EXPECT_GT(plain_growth, 2.0);  // the problem the rule is for
  double previous_growth = plain_growth;
  for (const double radius_leaves : {1.0, 1.5, 2.0}) {
    SCOPED_TRACE(radius_leaves);
    const double r = radius_leaves * leaf;
    const size_t merged_dense = voxels_after(dense, leaf, r);
    const double growth = double(merged_dense) / double(voxels_after(sparse, leaf, r));
    EXPECT_LT(growth, previous_growth);  // a larger radius saturates sooner
    previous_growth = growth;
    // Packing bound: a voxel opens only for a point farther than r from the nearby centroids,
    // so the map holds about one point per r-ball of the shell. Bound: balls of radius r / 2
    // packed into the +-5 sigma slab (every sample lies inside it with probability ~0.99) and
    // its r / 2 margins, at a packing density of at most 0.75 (Kepler).
    const double slab_m3 = 1.0 * 1.0 * (0.10 + r);
    const double ball_m3 = 4.0 / 3.0 * M_PI * std::pow(r / 2.0, 3);
    EXPECT_LT(double(merged_dense), 0.75 * slab_m3 / ball_m3);
  }
  EXPECT_LT(previous_growth, 1.3);  // two leaves: near saturation at the sparse density
}

TEST(VoxelAccumulator, RejectsBadLeafAndMergeRadius) {
  EXPECT_THROW(VoxelAccumulator(0.0), std::invalid_argument);
  EXPECT_THROW(VoxelAccumulator(0.1, -0.01), std::invalid_argument);
  EXPECT_THROW(VoxelAccumulator(0.1, std::nan("")), std::invalid_argument);
  EXPECT_THROW(VoxelAccumulator(0.1, 0.2001), std::invalid_argument);
  EXPECT_NO_THROW(VoxelAccumulator(0.1, 0.2));
}

}  // namespace
}  // namespace keel::mapping
