// nanoflann's dataset adaptor over a vector of points, and the 3-D kd-tree on it, shared by
// RadiusSearch and the plane map (nanoflann: header-only, Debian libnanoflann-dev).
#pragma once

#include <nanoflann.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace keel::mapping {

struct KdPoints {
  std::vector<Eigen::Vector3f> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(size_t index, size_t axis) const { return points[index][axis]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;  // let nanoflann compute it
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, KdPoints>,
                                                   KdPoints, 3, uint32_t>;

}  // namespace keel::mapping
