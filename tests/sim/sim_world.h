// What every simulated sensor needs from a scene: ray casts and, for cameras, a brightness.
#pragma once

#include <Eigen/Core>

namespace keel::sim {

struct RayHit {
  double range_m = 0.0;    // distance along the (unit) ray
  Eigen::Vector3d normal;  // unit surface normal at the hit, facing the ray origin side
  int surface = -1;        // primitive or triangle id
  bool returns = true;     // false: the surface absorbs range sensors (water surface)
  double albedo = 0.5;     // diffuse reflectivity in [0, 1]
};

class SimWorld {
 public:
  virtual ~SimWorld() = default;
  // Nearest hit along origin + t * dir (dir unit) with t in [t_min, t_max].
  virtual bool raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                       double t_max, RayHit* hit) const = 0;
  // Image brightness in [0, 1] seen along a camera ray; hit is null for a miss.
  virtual double shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                       const RayHit* hit) const = 0;
};

}  // namespace keel::sim
