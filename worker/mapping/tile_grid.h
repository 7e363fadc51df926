// Spatial tiles of a map, for processing it out of core (issue 17; PotreeConverter and Entwine
// chunk clouds the same way): cubes anchored at the origin whose edge is a power-of-two number
// of grid units, and which split into 8 children (level + 1) when one is too dense to process.
//
// A point's tile comes from its voxel index at the unit, floor(p / unit) per axis, the same
// arithmetic as VoxelAccumulator's: with the unit equal to the final chain's voxel leaf, every
// voxel lies in exactly one tile, so a tile holds all the points of each of its voxels.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {

struct TileKey {
  int32_t x = 0, y = 0, z = 0;
  uint8_t level = 0;  // 0: the base grid; each level halves the edge
  bool operator==(const TileKey& o) const {
    return x == o.x && y == o.y && z == o.z && level == o.level;
  }
  bool operator!=(const TileKey& o) const { return !(*this == o); }
  bool operator<(const TileKey& o) const;
  std::string to_string() const;  // "(x, y, z) level L"
};

struct TileKeyHash {
  size_t operator()(const TileKey& key) const;
};

// An axis-aligned box, metres.
struct Box {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  // The box grown by `margin` on every side.
  Box expanded(double margin) const;
  // Whether p lies in the closed box.
  bool contains(const Eigen::Vector3d& p) const;
};

class TileGrid {
 public:
  // Throws std::invalid_argument unless unit_m > 0 (finite) and units_per_tile is a power of two
  // in [1, 2^20].
  TileGrid(double unit_m, int64_t units_per_tile);

  // A grid of about `target_edge_m` tiles: the power of two of units nearest to it.
  static TileGrid with_edge_near(double unit_m, double target_edge_m);

  double unit_m() const { return unit_m_; }
  int64_t units_per_tile() const { return units_per_tile_; }
  // Levels below the base grid down to tiles of one unit.
  int max_level() const { return max_level_; }
  double edge_m(int level = 0) const;

  // The tile of the voxel (unit_m) holding p at `level`. Throws std::invalid_argument as
  // voxel_of does for coordinates whose index does not fit.
  TileKey tile_of(const Eigen::Vector3f& p, int level = 0) const;
  // The tile of voxel `voxel` of a grid of leaf `leaf_m` at `level`: for leaf_m == unit_m the
  // tile holding the voxel; otherwise the tile holding the voxel's minimum corner (a pure
  // function of the index, so every caller agrees on it).
  TileKey tile_of_voxel(const VoxelKey& voxel, double leaf_m, int level = 0) const;
  Box box(const TileKey& tile) const;
  // Child 0..7 (bit 0: upper half in x, bit 1: y, bit 2: z) and the parent.
  TileKey child(const TileKey& tile, int index) const;
  // The tiles around `home` whose halos may reach into it, each with its box grown by its halo,
  // and how deep inside home a point must lie to be in none of them: what for_each_halo_tile
  // needs, computed once for the many points of one tile. halo_m must grow with nothing but
  // the box's distance from the origin (as the filters' halos do), so a bounded neighbourhood
  // is searched. Throws std::invalid_argument when the halo spans too many tiles.
  struct HaloReach {
    TileKey home;
    Box home_box;
    double widest_m = 0.0;  // no neighbour's halo reaches deeper into home than this
    std::vector<std::pair<TileKey, Box>> neighbours;  // tile, its box grown by its halo
  };
  HaloReach halo_reach(const TileKey& home, const std::function<double(const Box&)>& halo_m) const;
  // Calls visit(tile) for every tile of p's level other than `home` whose box grown by
  // halo_m(tile's box) contains p (p in home).
  void for_each_halo_tile(const Eigen::Vector3f& p, const HaloReach& reach,
                          const std::function<void(const TileKey&)>& visit) const;
  void for_each_halo_tile(const Eigen::Vector3f& p, const TileKey& home,
                          const std::function<double(const Box&)>& halo_m,
                          const std::function<void(const TileKey&)>& visit) const;

 private:
  double unit_m_;
  double inverse_unit_;
  int64_t units_per_tile_;
  int max_level_ = 0;
};

}  // namespace keel::mapping
