#include "worker/ba/dvl_raycast_factor.h"

#include <ceres/autodiff_cost_function.h>

#include <cmath>

#include "worker/ba/jet_value.h"
#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// Beam origin and unit direction in the model frame for given variables.
template <typename T>
void beam_in_model(const ServoMount& mount, const DvlBeam& beam, const T* pose, const T* theta,
                   const T* T_world_model, Vec3<T>& origin_model, Vec3<T>& direction_model) {
  const Vec3<T> origin_world =
      mount.servo_to_world(pose, theta[0], Vec3<T>(beam.origin_servo.cast<T>()));
  const Vec3<T> direction_world =
      mount.servo_direction_to_world(pose, theta[0], Vec3<T>(beam.direction_servo.cast<T>()));
  // H_g^M of Eq. (5): world -> model is x_gM^-1.
  origin_model = inverse_transform_point(T_world_model, origin_world);
  direction_model = block_rotation(T_world_model).normalized().conjugate() * direction_world;
}

// The smooth normal may turn up to 30 degrees from the facet's (a crease's limit), so a beam
// hitting its facet at a steep but fine angle could be near-tangent to the smooth plane: a
// derivative scaled by 1 / (n.d) without bound, or a "grazing" miss. Where the smooth plane
// meets the beam at less than half the facet's n.d (or from the other side), the facet
// normal linearises instead.
Eigen::Vector3d linearising_normal(const RayHit& hit, const Eigen::Vector3d& direction,
                                   DvlRangeNormal normal) {
  if (normal == DvlRangeNormal::kFacet) return hit.face_normal;
  const double facet = hit.face_normal.dot(direction);
  const double smooth = hit.interpolated_normal.dot(direction);
  return smooth * facet > 0 && std::abs(smooth) >= 0.5 * std::abs(facet) ? hit.interpolated_normal
                                                                         : hit.face_normal;
}

// Range along the ray to the plane through the hit point of the chosen normal: differentiable
// in origin and direction; nullopt on a miss.
template <typename T>
std::optional<T> cast_range(const MeshQuery& mesh, const Vec3<T>& origin, const Vec3<T>& direction,
                            double max_range_m, DvlRangeNormal normal) {
  Ray ray;
  ray.origin = jet_value(origin);
  ray.direction = jet_value(direction);
  ray.max_range_m = max_range_m;
  const std::optional<RayHit> hit = mesh.raycast(ray);
  if (!hit) return std::nullopt;
  const Vec3<T> n = linearising_normal(*hit, ray.direction, normal).cast<T>();
  const T n_dot_d = n.dot(direction);
  if (std::abs(jet_value(n_dot_d)) < 1e-12) return std::nullopt;  // grazing: no range
  return T(n.dot(hit->point.cast<T>() - origin) / n_dot_d);
}

struct DvlRaycast {
  const MeshQuery* mesh;
  ServoMount mount;
  DvlBeam beam;
  double sigma_m, max_range_m, gate_m;
  DvlRangeNormal normal;

  template <typename T>
  bool operator()(const T* pose, const T* theta, const T* T_world_model, T* residual) const {
    Vec3<T> origin, direction;
    beam_in_model(mount, beam, pose, theta, T_world_model, origin, direction);
    const std::optional<T> range = cast_range(*mesh, origin, direction, max_range_m, normal);
    // Eq. (14): measured minus predicted, whitened.
    residual[0] = range ? (T(beam.range_m) - *range) / T(sigma_m) : T(gate_m / sigma_m);
    return true;
  }
};

}  // namespace

DvlBeam make_dvl_beam(const Pose3& T_servo_dvl, const Eigen::Vector3d& direction_dvl,
                      double range_m) {
  return DvlBeam{T_servo_dvl.translation(), T_servo_dvl.linear() * direction_dvl.normalized(),
                 range_m};
}

ceres::CostFunction* make_dvl_raycast_factor(const MeshQuery& mesh, const ServoMount& mount,
                                             const DvlBeam& beam, double sigma_m,
                                             double max_range_m, double gate_m,
                                             DvlRangeNormal normal) {
  return new ceres::AutoDiffCostFunction<DvlRaycast, 1, kPoseBlockSize, 1, kPoseBlockSize>(
      new DvlRaycast{&mesh, mount, beam, sigma_m, max_range_m, gate_m, normal});
}

std::optional<DvlHit> predict_dvl_hit(const MeshQuery& mesh, const ServoMount& mount,
                                      const DvlBeam& beam, const Pose3& T_world_vehicle,
                                      double servo_angle_rad, const Pose3& T_world_model,
                                      double max_range_m) {
  const PoseBlock pose = to_pose_block(T_world_vehicle);
  const PoseBlock model = to_pose_block(T_world_model);
  Eigen::Vector3d origin, direction;
  beam_in_model(mount, beam, pose.data(), &servo_angle_rad, model.data(), origin, direction);
  const std::optional<double> range =  // value only: the normal does not matter
      cast_range(mesh, origin, direction, max_range_m, DvlRangeNormal::kFacet);
  if (!range) return std::nullopt;
  return DvlHit{*range, origin + *range * direction};
}

std::optional<double> predict_dvl_range(const MeshQuery& mesh, const ServoMount& mount,
                                        const DvlBeam& beam, const Pose3& T_world_vehicle,
                                        double servo_angle_rad, const Pose3& T_world_model,
                                        double max_range_m) {
  const auto hit = predict_dvl_hit(mesh, mount, beam, T_world_vehicle, servo_angle_rad,
                                   T_world_model, max_range_m);
  return hit ? std::optional<double>(hit->range_m) : std::nullopt;
}

}  // namespace keel::ba
