// Filters over tiles equal filters over the whole map, point for point (issue 17): every tile
// filtered with its halo keeps exactly the points the whole-map chain keeps in its box, for
// voxel grids, ROR, DROR and crop boxes and chains of them, on clouds that straddle tile
// borders (points on the borders included), at the base level and at a split level.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/filter_chain.h"
#include "worker/mapping/tiled_filter.h"

namespace keel::mapping {
namespace {

using Point = std::array<float, 4>;  // x, y, z, intensity: compared bit for bit

std::vector<Point> as_points(const PointCloud& cloud) {
  std::vector<Point> points;
  for (size_t k = 0; k < cloud.size(); ++k)
    points.push_back({cloud.xyz[k].x(), cloud.xyz[k].y(), cloud.xyz[k].z(),
                      cloud.has_intensity() ? cloud.intensity[k] : 0.f});
  std::sort(points.begin(), points.end());
  return points;
}

// Clustered points around tile borders of a 0.8 m grid (unit 0.1 m), some exactly on a border
// or a voxel face, in [-1.7, 1.7]^3; intensity = index.
PointCloud straddling_cloud(size_t n, unsigned seed) {
  PointCloud cloud = testing::random_cloud(n, -1.7f, 1.7f, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_int_distribution<int> face(-2, 2);
  std::uniform_real_distribution<float> jitter(-0.03f, 0.03f);
  for (size_t k = 0; k < n / 4; ++k) {  // a quarter within 3 cm of a border, on it every 8th
    Eigen::Vector3f& p = cloud.xyz[k];
    const int axis = static_cast<int>(k % 3);
    p[axis] = 0.8f * static_cast<float>(face(rng)) + (k % 8 == 0 ? 0.f : jitter(rng));
  }
  for (size_t k = n / 4; k < n / 3; ++k) cloud.xyz[k].x() = 0.1f * static_cast<float>(face(rng));
  return cloud;
}

struct TiledResult {
  std::vector<Point> points;
  std::vector<FilterStep> steps;
  size_t tiles = 0, halo_points = 0;
};

// Splits `cloud` into the tiles of `level` and their halos as the map stage spills them (the
// grid's tile_of and for_each_halo_tile, feed order kept), filters each tile and gathers the
// owned points.
TiledResult filter_by_tiles(const FilterChain& chain, const TileGrid& grid, const PointCloud& cloud,
                            int level) {
  std::map<TileKey, std::vector<size_t>> core, halo;
  const auto halo_of = [&](const Box& box) { return chain_halo_m(chain, grid, box); };
  const bool has_halo = halo_of(grid.box(TileKey{})) > 0.0;  // as the map stage's binner
  for (size_t k = 0; k < cloud.size(); ++k) {
    const TileKey home = grid.tile_of(cloud.xyz[k], level);
    core[home].push_back(k);
    if (has_halo)
      grid.for_each_halo_tile(cloud.xyz[k], home, halo_of,
                            [&](const TileKey& other) { halo[other].push_back(k); });
  }
  TiledResult result;
  for (const auto& [tile, members] : core) {
    TileWork work;
    const std::vector<size_t>* lists[] = {&members, &halo[tile]};
    for (const std::vector<size_t>* list : lists)
      for (const size_t k : *list) {
        work.points.xyz.push_back(cloud.xyz[k]);
        work.points.intensity.push_back(cloud.intensity[k]);
        work.owned.push_back(list == &members);
      }
    result.halo_points += halo[tile].size();
    const auto steps = filter_tile(chain, grid, tile, work, 2);
    if (result.steps.empty()) {
      result.steps = steps;
    } else {
      for (size_t s = 0; s < steps.size(); ++s) {
        result.steps[s].points_in += steps[s].points_in;
        result.steps[s].points_out += steps[s].points_out;
      }
    }
    const auto kept = as_points(work.points);
    result.points.insert(result.points.end(), kept.begin(), kept.end());
    ++result.tiles;
  }
  std::sort(result.points.begin(), result.points.end());
  return result;
}

void expect_tiles_equal_whole(const std::string& chain_json, const PointCloud& cloud, int level,
                              bool expect_halo) {
  SCOPED_TRACE(chain_json + " level " + std::to_string(level));
  const FilterChain chain = filter_chain_from_json(nlohmann::json::parse(chain_json), "chain");
  const TileGrid grid(tile_unit_for(chain, 0.1), 8);  // 0.8 m tiles at level 0 for unit 0.1
  PointCloud whole = cloud;
  const std::vector<FilterStep> whole_steps = apply_filter_chain(chain, whole, 2);
  const TiledResult tiled = filter_by_tiles(chain, grid, cloud, level);
  EXPECT_GT(tiled.tiles, 20u);
  EXPECT_EQ(tiled.halo_points > 0, expect_halo);
  ASSERT_GT(whole.size(), 0u);
  EXPECT_LT(whole.size(), cloud.size());  // the chain removes something: the test can fail
  ASSERT_EQ(tiled.points.size(), whole.size());
  EXPECT_TRUE(tiled.points == as_points(whole));  // bit for bit
  ASSERT_EQ(tiled.steps.size(), whole_steps.size());
  for (size_t s = 0; s < whole_steps.size(); ++s) {
    EXPECT_EQ(tiled.steps[s].filter, whole_steps[s].filter);
    EXPECT_EQ(tiled.steps[s].points_in, whole_steps[s].points_in);
    EXPECT_EQ(tiled.steps[s].points_out, whole_steps[s].points_out);
  }
}

TEST(TiledFilter, VoxelGridNeedsNoHaloAndKeepsEveryCentroidBitForBit) {
  const PointCloud cloud = straddling_cloud(20000, 1);
  for (int level : {0, 1})
    expect_tiles_equal_whole(R"([{"type": "voxel_grid", "leaf": 0.1}])", cloud, level, false);
}

TEST(TiledFilter, RadiusOutlierRemoval) {
  const PointCloud cloud = straddling_cloud(20000, 2);
  for (int level : {0, 1})
    expect_tiles_equal_whole(R"([{"type": "ror", "radius": 0.15, "min_neighbors": 2}])", cloud,
                             level, true);
}

TEST(TiledFilter, DynamicRadiusOutlierRemovalWithRangeFromTheOrigin) {
  const PointCloud cloud = straddling_cloud(20000, 3);
  // Radius max(3 * 2 deg * r_xy, 0.05): 0.05 m near the origin, 0.25 m at the corners.
  for (int level : {0, 1})
    expect_tiles_equal_whole(
        R"([{"type": "dror", "beta": 3.0, "alpha_deg": 2.0, "k_min": 4, "sr_min": 0.05}])", cloud,
        level, true);
}

TEST(TiledFilter, CropBoxes) {
  const PointCloud cloud = straddling_cloud(20000, 4);
  expect_tiles_equal_whole(R"([{"type": "crop_box", "min": [-1.2, -0.8, -1.6],
                                "max": [1.6, 0.8, 0.4], "remove": "outside"},
                               {"type": "crop_box", "min": [-0.4, -0.4, -0.4],
                                "max": [0.8, 0.4, 0.4], "remove": "inside"}])",
                           cloud, 0, false);
}

TEST(TiledFilter, ChainsMixingNeighbourhoodsAndVoxels) {
  const PointCloud cloud = straddling_cloud(30000, 5);
  for (int level : {0, 1}) {
    expect_tiles_equal_whole(R"([{"type": "crop_box", "min": [-1.5, -1.5, -1.5],
                                  "max": [1.5, 1.5, 1.5]},
                                 {"type": "ror", "radius": 0.12, "min_neighbors": 1},
                                 {"type": "voxel_grid", "leaf": 0.1}])",
                             cloud, level, true);
    // A voxel grid before ROR: the halo needs whole voxels around the ROR radius.
    expect_tiles_equal_whole(R"([{"type": "voxel_grid", "leaf": 0.1},
                                 {"type": "ror", "radius": 0.2, "min_neighbors": 3}])",
                             cloud, level, true);
  }
}

TEST(TiledFilter, HaloOfAChain) {
  const TileGrid grid(0.1, 8);
  const Box box{Eigen::Vector3d(0.8, 0.8, 0), Eigen::Vector3d(1.6, 1.6, 0.8)};
  const auto halo = [&](const std::string& json) {
    return chain_halo_m(filter_chain_from_json(nlohmann::json::parse(json), "c"), grid, box);
  };
  EXPECT_EQ(halo(R"([{"type": "voxel_grid", "leaf": 0.1}])"), 0.0);
  EXPECT_EQ(halo(R"([{"type": "crop_box", "min": [0,0,0], "max": [1,1,1]}])"), 0.0);
  EXPECT_NEAR(halo(R"([{"type": "ror", "radius": 0.3}])"), 0.3 + kHaloMarginM, 1e-12);
  EXPECT_NEAR(halo(R"([{"type": "voxel_grid", "leaf": 0.1}, {"type": "ror", "radius": 0.3}])"),
              0.3 + 0.1 + 2 * kHaloMarginM, 1e-12);
  // A leaf other than the unit: whole voxels even for the tile's own output.
  EXPECT_NEAR(halo(R"([{"type": "voxel_grid", "leaf": 0.25}])"), 0.25 + kHaloMarginM, 1e-12);
  // DROR at the box grown by what follows it, farthest corner (1.6 + 0.3, 1.6 + 0.3).
  const double r_xy = std::hypot(1.9 + kHaloMarginM, 1.9 + kHaloMarginM);
  EXPECT_NEAR(halo(R"([{"type": "dror", "beta": 3.0, "alpha_deg": 2.0, "sr_min": 0.01},
                       {"type": "ror", "radius": 0.3}])"),
              0.3 + kHaloMarginM + 3.0 * 2.0 * M_PI / 180.0 * r_xy + kHaloMarginM, 1e-12);
}

TEST(TiledFilter, GridArithmetic) {
  const TileGrid grid(0.02, 512);
  EXPECT_DOUBLE_EQ(grid.edge_m(), 10.24);
  EXPECT_DOUBLE_EQ(grid.edge_m(2), 2.56);
  EXPECT_EQ(grid.max_level(), 9);
  EXPECT_EQ(grid.tile_of(Eigen::Vector3f(-0.01f, 10.25f, 0.f)), (TileKey{-1, 1, 0, 0}));
  EXPECT_EQ(grid.tile_of(Eigen::Vector3f(-0.01f, 10.25f, 0.f), 1), (TileKey{-1, 2, 0, 1}));
  // Children nest in their parent and tile it.
  const TileKey parent{3, -2, 1, 0};
  for (int c = 0; c < 8; ++c) {
    const TileKey child = grid.child(parent, c);
    const Box b = grid.box(child), p = grid.box(parent);
    EXPECT_TRUE(p.expanded(1e-9).contains(b.min) && p.expanded(1e-9).contains(b.max));
    EXPECT_EQ(grid.tile_of(((b.min + b.max) / 2).cast<float>(), 0), parent);
  }
  EXPECT_EQ(TileGrid::with_edge_near(0.02, 10.0).units_per_tile(), 512);
  EXPECT_EQ(TileGrid::with_edge_near(0.05, 10.0).units_per_tile(), 256);
  EXPECT_THROW(TileGrid(0.02, 3), std::invalid_argument);
  EXPECT_THROW(TileGrid(-1.0, 4), std::invalid_argument);
  // A voxel of another leaf belongs to the tile of its minimum corner.
  EXPECT_EQ(grid.tile_of_voxel(VoxelKey{41, -1, 0}, 0.256, 0), (TileKey{1, -1, 0, 0}));
}

}  // namespace
}  // namespace keel::mapping
