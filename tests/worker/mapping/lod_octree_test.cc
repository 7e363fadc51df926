// The LOD octree (issue 17): finest cubes partition the points (each exactly once, in its
// cube), each coarser cube's points are a subset of its children's, the thinning keeps exactly
// one point per occupied cell (the one nearest the cell's centre, found here by brute force),
// and cubes split until they hold at most the cap.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "worker/mapping/lod_octree.h"

namespace keel::mapping {
namespace {

using Key = std::array<float, 4>;  // x, y, z, the point's id (attribute 0)

Key key_of(const LodPoints& points, size_t k) {
  return {points.xyz[k].x(), points.xyz[k].y(), points.xyz[k].z(), points.attributes[0][k]};
}

// A noisy plane and a cluster in the cube [0, 8)^3; attribute 0 = id, attribute 1 = 2 * id.
LodPoints test_points(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 8.f);
  std::normal_distribution<float> noise(0.f, 0.02f);
  LodPoints points = LodPoints::with_attributes(2);
  for (size_t k = 0; k < n; ++k) {
    Eigen::Vector3f p(u(rng), u(rng), 2.f + noise(rng));
    if (k % 5 == 0) p = Eigen::Vector3f(6.f + 0.1f * noise(rng), 6.f + noise(rng), u(rng) / 4);
    points.xyz.push_back(p.cwiseMax(0.f).cwiseMin(7.999f));
    points.attributes[0].push_back(static_cast<float>(k));
    points.attributes[1].push_back(2.f * static_cast<float>(k));
  }
  return points;
}

TEST(LodOctree, FinestCubesPartitionThePointsAndCoarserOnesAreSubsets) {
  const LodPoints input = test_points(60000, 1);
  LodOptions options;
  options.max_points_per_tile = 5000;
  options.cells_per_edge = 16;
  std::map<std::string, LodNode> nodes;
  std::map<std::string, std::vector<Key>> contents;
  const LodWrite write = [&](const LodNode& node, const LodPoints& points) {
    EXPECT_FALSE(nodes.count(node.name)) << node.name << " written twice";
    for (const int c : node.children)
      EXPECT_TRUE(nodes.count(node.name + std::to_string(c))) << "child after parent";
    nodes[node.name] = node;
    std::vector<Key>& keys = contents[node.name];
    for (size_t k = 0; k < points.size(); ++k) {
      keys.push_back(key_of(points, k));
      EXPECT_EQ(points.attributes[1][k], 2.f * points.attributes[0][k]);  // attributes follow
      const Eigen::Vector3d p = points.xyz[k].cast<double>();
      EXPECT_TRUE(((p - node.cube.min).array() >= 0).all() &&
                  ((p - node.cube.min).array() < node.cube.edge_m).all())
          << node.name;
    }
    std::sort(keys.begin(), keys.end());
    EXPECT_EQ(node.points, points.size());
  };
  LodNode root;
  build_lod_subtree("r", LodCube{Eigen::Vector3d::Zero(), 8.0}, input, options, write, &root);
  EXPECT_EQ(root.name, "r");
  EXPECT_GT(nodes.size(), 20u);

  std::multiset<Key> finest;
  for (const auto& [name, node] : nodes) {
    if (node.children.empty()) {
      EXPECT_EQ(node.geometric_error_m, 0.0);
      EXPECT_LE(node.points, options.max_points_per_tile);
      finest.insert(contents[name].begin(), contents[name].end());
      continue;
    }
    EXPECT_DOUBLE_EQ(node.geometric_error_m, node.cube.edge_m / 16);
    std::vector<Key> below;
    for (const int c : node.children) {
      const auto& child = contents[name + std::to_string(c)];
      below.insert(below.end(), child.begin(), child.end());
      EXPECT_DOUBLE_EQ(nodes[name + std::to_string(c)].cube.edge_m, node.cube.edge_m / 2);
    }
    std::sort(below.begin(), below.end());
    EXPECT_TRUE(
        std::includes(below.begin(), below.end(), contents[name].begin(), contents[name].end()))
        << name << " holds a point none of its children holds";
    EXPECT_LT(contents[name].size(), below.size());
  }
  // Every input point in exactly one finest cube.
  std::multiset<Key> all;
  for (size_t k = 0; k < input.size(); ++k) all.insert(key_of(input, k));
  EXPECT_TRUE(finest == all);
}

TEST(LodOctree, ThinningKeepsThePointNearestEachOccupiedCellsCentre) {
  const LodPoints input = test_points(20000, 2);
  const LodCube cube{Eigen::Vector3d::Zero(), 8.0};
  const int cells = 32;
  const LodPoints thinned = thin_points(input, cube, cells);
  // Brute force: per cell, the nearest point to its centre (first on ties).
  std::map<std::array<int, 3>, std::pair<double, size_t>> best;
  const double cell = 8.0 / cells;
  for (size_t k = 0; k < input.size(); ++k) {
    std::array<int, 3> c;
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      c[a] = std::min(cells - 1, static_cast<int>(std::floor(input.xyz[k][a] / cell)));
      const double d = input.xyz[k][a] / cell - (c[a] + 0.5);
      d2 += d * d;
    }
    const auto it = best.find(c);
    if (it == best.end() || d2 < it->second.first) best[c] = {d2, k};
  }
  ASSERT_EQ(thinned.size(), best.size());
  std::set<float> expected_ids;
  for (const auto& [c, b] : best) expected_ids.insert(input.attributes[0][b.second]);
  const std::set<float> ids(thinned.attributes[0].begin(), thinned.attributes[0].end());
  EXPECT_TRUE(ids == expected_ids);
  // Evenness: no two kept points share a cell.
  EXPECT_EQ(ids.size(), thinned.size());
}

TEST(LodOctree, ManyPointsAtOneSpotStopAtTheSmallestCube) {
  LodPoints points = LodPoints::with_attributes(1);
  for (int k = 0; k < 3000; ++k) {
    points.xyz.emplace_back(1.f, 1.f, 1.f);
    points.attributes[0].push_back(static_cast<float>(k));
  }
  LodOptions options;
  options.max_points_per_tile = 100;
  options.min_edge_m = 0.5;
  size_t finest_points = 0, nodes = 0;
  build_lod_subtree(
      "r", LodCube{Eigen::Vector3d::Zero(), 4.0}, points, options,
      [&](const LodNode& node, const LodPoints& p) {
        ++nodes;
        EXPECT_GE(node.cube.edge_m, 0.5);
        if (node.children.empty()) finest_points += p.size();
      },
      nullptr);
  EXPECT_EQ(finest_points, 3000u);
  EXPECT_EQ(nodes, 4u);  // 4 m, 2 m, 1 m, 0.5 m
}

}  // namespace
}  // namespace keel::mapping
