// Every point within one cell of another lies in the 3 x 3 x 3 block around its cell.
#include "worker/mapping/cell_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/worker/mapping/test_clouds.h"

namespace keel::mapping {
namespace {

TEST(CellGrid, BlocksHoldEveryNeighbourWithinOneCell) {
  PointCloud cloud = testing::random_cloud(2000, -1.0f, 1.0f, 5);
  cloud.xyz.push_back({-1e6f, 3.0f, 2.0f});  // a far outlier gets a cell of its own
  const double cell = 0.2;
  const CellGrid grid(cloud.xyz, cell);
  // Each point stored exactly once.
  std::vector<uint32_t> seen = grid.input_index();
  std::sort(seen.begin(), seen.end());
  for (size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], i);
  std::vector<uint32_t> block;
  for (size_t c = 0; c < grid.cell_count(); ++c) {
    grid.block_around(c, &block);
    ASSERT_TRUE(std::find(block.begin(), block.end(), c) != block.end());
    std::vector<uint32_t> in_block;
    for (const uint32_t b : block) {
      for (uint32_t i = grid.begin(b); i < grid.end(b); ++i)
        in_block.push_back(grid.input_index()[i]);
    }
    std::sort(in_block.begin(), in_block.end());
    for (uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
      const Eigen::Vector3f& p = cloud.xyz[grid.input_index()[i]];
      for (size_t k = 0; k < cloud.size(); ++k) {
        if ((cloud.xyz[k] - p).norm() < cell) {
          ASSERT_TRUE(std::binary_search(in_block.begin(), in_block.end(), k)) << k;
        }
      }
    }
  }
  EXPECT_THROW(CellGrid(cloud.xyz, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace keel::mapping
