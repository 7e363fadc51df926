// Internal to keel_mesh_io: the position error Draco's quantization introduced, measured by
// comparing the input positions with the decoded ones (for draco_codec.cc's round trips).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <vector>

#include "worker/io/draco/draco_codec.h"

namespace draco {
class PointCloud;
}

namespace keel::io {

// One pass over the positions: per-axis extremes in float (as Draco's
// AttributeQuantizationTransform computes them) and the largest |coordinate| (for the
// float-rounding allowance of error_tolerance).
struct PositionBounds {
  Eigen::Vector3f min = Eigen::Vector3f::Zero(), max = Eigen::Vector3f::Zero();
  double largest_abs = 0.0;
  bool empty = true;

  template <typename Vector>
  void add(const Vector& p) {
    const Eigen::Vector3f f = p.template cast<float>();
    min = empty ? f : Eigen::Vector3f(min.cwiseMin(f));
    max = empty ? f : Eigen::Vector3f(max.cwiseMax(f));
    empty = false;
    largest_abs = std::max(largest_abs, p.template cast<double>().cwiseAbs().maxCoeff());
  }
};

// A point cloud's positions as consecutive parts (a combined map's sensor maps): encoded and
// measured as their concatenation, without building it.
using PositionParts = std::vector<const std::vector<Eigen::Vector3f>*>;

PositionBounds position_bounds(const PositionParts& parts);

// Draco quantizes positions on a cube of side `range` = the largest extent of the float
// positions (1 when they all coincide), in 2^bits - 1 steps: records the range and half a
// step's diagonal, and returns that plus an allowance for float rounding of large coordinates.
double error_tolerance(const PositionBounds& bounds, const DracoOptions& options,
                       DracoEncoded* result);

// The largest distance from each original point (those `used` marks, when not null) to the
// nearest decoded point; error_method "nearest_decoded". For Eigen::Vector3f and Vector3d.
template <typename Vector>
void measure_error(const std::vector<Vector>& originals, const std::vector<bool>* used,
                   const std::vector<Eigen::Vector3f>& decoded, const DracoOptions& options,
                   DracoEncoded* result);

// The point cloud's error predicted with Draco's quantizer arithmetic (error_method "replica");
// false (nothing measured) when the decoded points differ from the prediction.
bool measure_error_by_replica(const PositionParts& originals, const PositionBounds& bounds,
                              const draco::PointCloud& decoded, const DracoOptions& options,
                              double tolerance, DracoEncoded* result);

}  // namespace keel::io
