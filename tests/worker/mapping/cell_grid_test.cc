// Every point within one cell of another lies in the 3 x 3 x 3 block around its cell.
#include "worker/mapping/cell_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/worker/mapping/test_clouds.h"

namespace keel::mapping {
namespace {

// Every stored point once; every block holds every point within one cell of each point of its
// cell (brute force), and only cells whose indices differ by at most one per axis.
void expect_blocks_complete(const std::vector<Eigen::Vector3f>& points, double cell) {
  const CellGrid grid(points, cell);
  std::vector<uint32_t> seen = grid.input_index();
  std::sort(seen.begin(), seen.end());
  ASSERT_EQ(seen.size(), points.size());
  for (size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], i);
  auto cell_of = [&](uint32_t stored) {
    const Eigen::Vector3f& p = points[grid.input_index()[stored]];
    return Eigen::Vector3d(std::floor(p.x() / cell), std::floor(p.y() / cell),
                           std::floor(p.z() / cell));
  };
  std::vector<uint32_t> block;
  for (size_t c = 0; c < grid.cell_count(); ++c) {
    // Points of one cell share its indices.
    for (uint32_t i = grid.begin(c); i < grid.end(c); ++i)
      ASSERT_EQ(cell_of(i), cell_of(grid.begin(c)));
    grid.block_around(c, &block);
    ASSERT_TRUE(std::is_sorted(block.begin(), block.end()));
    ASSERT_TRUE(std::find(block.begin(), block.end(), c) != block.end());
    std::vector<uint32_t> in_block;
    for (const uint32_t b : block) {
      ASSERT_LE((cell_of(grid.begin(b)) - cell_of(grid.begin(c))).cwiseAbs().maxCoeff(), 1.0);
      for (uint32_t i = grid.begin(b); i < grid.end(b); ++i)
        in_block.push_back(grid.input_index()[i]);
    }
    std::sort(in_block.begin(), in_block.end());
    for (uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
      const Eigen::Vector3f& p = points[grid.input_index()[i]];
      for (size_t k = 0; k < points.size(); ++k) {
        if ((points[k] - p).norm() < cell) {
          ASSERT_TRUE(std::binary_search(in_block.begin(), in_block.end(), k)) << k;
        }
      }
    }
  }
}

TEST(CellGrid, BlocksHoldEveryNeighbourWithinOneCell) {
  PointCloud cloud = testing::random_cloud(2000, -1.0f, 1.0f, 5);
  cloud.xyz.push_back({-1e6f, 3.0f, 2.0f});  // a far outlier gets a cell of its own
  expect_blocks_complete(cloud.xyz, 0.2);
}

TEST(CellGrid, ExtentsTooWideToPackAreGapCompressed) {
  // Three lattices 3000 km apart on every axis at 1 m cells: 2^23 cell indices per axis, 69
  // bits packed densely. Every cell of each lattice is occupied (points 0.5 m apart, exact in
  // float there), so a block reaching across a gap to the next lattice would be caught.
  std::vector<Eigen::Vector3f> points;
  for (const float far : {-3e6f, 0.0f, 3e6f}) {
    for (int i = -3; i <= 3; ++i) {
      for (int j = -3; j <= 3; ++j) {
        for (int k = -3; k <= 3; ++k) {
          points.push_back(Eigen::Vector3f(0.5f * i, 0.5f * j, 0.5f * k) +
                           Eigen::Vector3f(far, -far, far));
        }
      }
    }
  }
  expect_blocks_complete(points, 1.0);
}

TEST(CellGrid, SweepFindsTheSameBlocksAsSearch) {
  const PointCloud cloud = testing::random_cloud(3000, -2.0f, 2.0f, 7);
  const CellGrid grid(cloud.xyz, 0.25);
  CellGrid::BlockFinder finder(grid);
  std::vector<uint32_t> swept, searched;
  // Increasing with gaps, then back to the start (a restart), then increasing again.
  std::vector<size_t> visits;
  for (size_t c = 0; c < grid.cell_count(); c += 1 + c % 3) visits.push_back(c);
  for (size_t c = 0; c < grid.cell_count(); c += 5) visits.push_back(c);
  for (const size_t c : visits) {
    finder.block_around(c, &swept);
    grid.block_around(c, &searched);
    ASSERT_EQ(swept, searched) << c;
  }
}

TEST(CellGrid, RejectsBadInput) {
  const std::vector<Eigen::Vector3f> points{{0, 0, 0}, {1, 1, 1}};
  EXPECT_THROW(CellGrid(points, 0.0), std::invalid_argument);
  EXPECT_THROW(CellGrid(points, std::nan("")), std::invalid_argument);
  EXPECT_THROW(CellGrid({{0, 0, 0}, {0, std::nanf(""), 0}}, 0.25), std::invalid_argument);
  EXPECT_THROW(CellGrid({{0, 0, 0}, {3e38f, 0, 0}}, 1e-3), std::invalid_argument);  // > 2^62
  EXPECT_EQ(CellGrid({}, 0.25).cell_count(), 0u);
}

}  // namespace
}  // namespace keel::mapping
