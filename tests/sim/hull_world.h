// The real hull as the sensors see it: the CAD mesh placed at T_world_cad plus the foreign
// objects, with visual landmarks (dark and bright blobs SIFT can find) painted on it and
// lit by the vehicle's own LED (seed 001 Fig. 4) through attenuating water.
#pragma once

#include <memory>
#include <unordered_map>
#include <vector>

#include "tests/sim/hull_model.h"
#include "tests/sim/mesh_bvh.h"
#include "tests/sim/sim_world.h"

namespace keel::sim {

struct HullWorldOptions {
  double water_attenuation_per_m = 0.12;  // beam attenuation c (1/m), two-way path
  double reference_range_m = 1.5;         // range at which the LED gives albedo * cos
  double background = 0.04;               // open water
};

class HullWorld : public SimWorld {
 public:
  HullWorld(TriangleMesh real_mesh_world, std::vector<Landmark> landmarks,
            const HullWorldOptions& options = {});

  bool raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
               double t_max, RayHit* hit) const override;
  double shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
               const RayHit* hit) const override;

  // Albedo of the painted hull at a surface point (base paint, stains and landmark blobs).
  double albedo_at(const Eigen::Vector3d& p_world) const;
  const std::vector<Landmark>& landmarks() const { return landmarks_; }
  const MeshBvh& bvh() const { return bvh_; }

 private:
  static int64_t cell_key(int64_t x, int64_t y, int64_t z);
  MeshBvh bvh_;
  std::vector<Landmark> landmarks_;
  HullWorldOptions options_;
  double cell_m_ = 0.1;
  double max_radius_m_ = 0.0;
  std::unordered_map<int64_t, std::vector<int>> grid_;
};

}  // namespace keel::sim
