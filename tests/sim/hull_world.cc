#include "tests/sim/hull_world.h"

#include <algorithm>
#include <cmath>

#include "tests/sim/analytic_scene.h"

namespace keel::sim {

int64_t HullWorld::cell_key(int64_t x, int64_t y, int64_t z) {
  return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
}

HullWorld::HullWorld(TriangleMesh real_mesh_world, std::vector<Landmark> landmarks,
                     const HullWorldOptions& options)
    : bvh_(real_mesh_world), landmarks_(std::move(landmarks)), options_(options) {
  for (const auto& lm : landmarks_) max_radius_m_ = std::max(max_radius_m_, lm.radius_m);
  cell_m_ = std::max(0.1, 2.0 * max_radius_m_);
  for (size_t i = 0; i < landmarks_.size(); ++i) {
    const Eigen::Vector3d c = (landmarks_[i].p_world / cell_m_).array().floor();
    grid_[cell_key(int64_t(c.x()), int64_t(c.y()), int64_t(c.z()))].push_back(static_cast<int>(i));
  }
}

bool HullWorld::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
                        double t_max, RayHit* hit) const {
  MeshHit mh;
  if (!bvh_.raycast(origin, dir, t_min, t_max, &mh)) return false;
  hit->range_m = mh.t;
  Eigen::Vector3d n = bvh_.normal(mh.triangle);
  if (n.dot(dir) > 0.0) n = -n;
  hit->normal = n;
  hit->surface = mh.triangle;
  hit->returns = true;
  hit->albedo = albedo_at(origin + mh.t * dir);
  return true;
}

double HullWorld::albedo_at(const Eigen::Vector3d& p) const {
  // Base paint with low-frequency stains and fine grain.
  double albedo = 0.42 + 0.25 * (value_noise(p * 0.8) - 0.5) + 0.08 * (value_noise(p * 25.0) - 0.5);
  const Eigen::Vector3d lo = ((p.array() - max_radius_m_) / cell_m_).floor();
  const Eigen::Vector3d hi = ((p.array() + max_radius_m_) / cell_m_).floor();
  double best_weight = 0.0;
  for (int64_t x = int64_t(lo.x()); x <= int64_t(hi.x()); ++x)
    for (int64_t y = int64_t(lo.y()); y <= int64_t(hi.y()); ++y)
      for (int64_t z = int64_t(lo.z()); z <= int64_t(hi.z()); ++z) {
        const auto it = grid_.find(cell_key(x, y, z));
        if (it == grid_.end()) continue;
        for (int i : it->second) {
          const Landmark& lm = landmarks_[i];
          const double r = (p - lm.p_world).norm();
          if (r >= lm.radius_m) continue;
          // Flat blob with a soft rim over the outer 30% of its radius.
          const double weight = std::clamp((lm.radius_m - r) / (0.3 * lm.radius_m), 0.0, 1.0);
          if (weight > best_weight) {
            best_weight = weight;
            albedo = albedo * (1.0 - weight) + lm.albedo * weight;
          }
        }
      }
  return std::clamp(albedo, 0.0, 1.0);
}

double HullWorld::shade(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        const RayHit* hit) const {
  if (hit == nullptr) return options_.background;
  // LED co-located with the camera: Lambertian, inverse-square falloff, two-way attenuation.
  const double r = hit->range_m;
  const double cosine = std::max(0.0, -hit->normal.dot(dir));
  const double falloff = options_.reference_range_m * options_.reference_range_m / (r * r);
  const double attenuation =
      std::exp(-2.0 * options_.water_attenuation_per_m * (r - options_.reference_range_m));
  return std::clamp(options_.background + hit->albedo * cosine * falloff * attenuation, 0.0, 1.0);
}

}  // namespace keel::sim
