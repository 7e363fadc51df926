// Level-of-detail octree of a map for viewing (issue 17; Potree and Entwine build the same
// kind): cubes split into 8 children until a cube holds at most max_points_per_tile points;
// those finest cubes hold the map's points, each exactly once, and every coarser cube holds an
// even thinning of its children's points: per cell of a grid of cells_per_edge^3 over the cube,
// the point nearest the cell's centre. A coarser cube's points are thus a subset of its
// children's, so a viewer that shows a coarse cube instead of its children (3D Tiles
// "REPLACE" refinement) shows part of the same map, at a spacing of one cell.
//
// Node names are paths: "r" for the root, then one digit 0..7 per level, the child index
// x + 2y + 4z with a bit set for the upper half along that axis.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace keel::mapping {

// Points with float attributes (intensity, sensor, metrics: the caller names them), each
// attribute one value per point.
struct LodPoints {
  std::vector<Eigen::Vector3f> xyz;
  std::vector<std::vector<float>> attributes;

  size_t size() const { return xyz.size(); }
  // An empty set with `attribute_count` attributes.
  static LodPoints with_attributes(size_t attribute_count);
  void push_back(const LodPoints& from, size_t index);
  void append(const LodPoints& from);
};

struct LodCube {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  double edge_m = 1.0;
  Eigen::Vector3d center() const { return min + Eigen::Vector3d::Constant(edge_m / 2); }
  LodCube child(int index) const;
};

struct LodOptions {
  // Finest cubes hold at most this many points (unless a cube would be smaller than
  // min_edge_m: many points at one spot stay together).
  size_t max_points_per_tile = 100000;
  // Thinning grid of a coarser cube (Potree's spacing is its cube's edge / 128).
  int cells_per_edge = 128;
  double min_edge_m = 0.01;
};

struct LodNode {
  std::string name;
  LodCube cube;
  // The thinning cell's edge in metres for a coarser node (what is lost by not refining it), 0
  // for a finest one.
  double geometric_error_m = 0.0;
  std::vector<int> children;  // indices 0..7 of the children that hold points
  size_t points = 0;
};

using LodWrite = std::function<void(const LodNode& node, const LodPoints& points)>;

// The even thinning of `points` over `cube` (see above); points outside the cube count in its
// border cells. Deterministic: ties go to the earlier point, output in input order.
LodPoints thin_points(const LodPoints& points, const LodCube& cube, int cells_per_edge);

// The octree below `cube` (named `name`) over `points`, which must lie in the cube: calls
// write(node, its points) for every node, children before their parent, and returns the node's
// points (all of them for a finest cube, else the thinning) and the node itself.
LodPoints build_lod_subtree(const std::string& name, const LodCube& cube, LodPoints points,
                            const LodOptions& options, const LodWrite& write, LodNode* node);

// A coarser node over children built elsewhere (tiles processed one at a time): its points are
// the thinning of the union of the children's points. `children` pairs each child index with
// that child's points. Calls write and returns the node's points.
LodPoints build_lod_parent(const std::string& name, const LodCube& cube,
                           const std::vector<std::pair<int, LodPoints>>& children,
                           const LodOptions& options, const LodWrite& write, LodNode* node);

}  // namespace keel::mapping
