#include "worker/ba/surface_factor.h"

#include <ceres/autodiff_cost_function.h>

#include <algorithm>
#include <cmath>

#include "worker/ba/jet_value.h"
#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// Below this distance the direction p -> l is numerically meaningless; use the normal.
constexpr double kOnSurfaceM = 1e-9;

// Eq. (5) with p and u from the closest point at the current value (see the header).
template <typename T>
T signed_distance(const MeshQuery& mesh, const Vec3<T>& landmark_model) {
  const ClosestPoint closest = mesh.closest_point(jet_value(landmark_model));
  Eigen::Vector3d u = closest.normal;
  if (closest.distance_m > kOnSurfaceM) {
    const double sign = closest.signed_distance_m < 0 ? -1.0 : 1.0;
    u = sign * (jet_value(landmark_model) - closest.point) / closest.distance_m;
  }
  return (landmark_model - closest.point.cast<T>()).dot(u.cast<T>());
}

struct Surface {
  const MeshQuery* mesh;
  MaxMixture mixture;
  SurfaceMode mode;
  double offset_m;
  uint8_t* label_slot;

  template <typename T>
  bool operator()(const T* T_world_model, const T* landmark, T* residual) const {
    const Vec3<T> l_world(landmark[0], landmark[1], landmark[2]);
    const Vec3<T> l_model = inverse_transform_point(T_world_model, l_world);  // H_g^M l_i
    const T error = T(offset_m) - signed_distance(*mesh, l_model);            // z_s - h
    const int label = mixture.label(jet_value(error));                        // Eq. (7)
    if constexpr (is_jet<T>()) {
      if (label_slot != nullptr) *label_slot = static_cast<uint8_t>(label);
    }
    const int used = mode == SurfaceMode::kOnModel ? 1 : label;
    residual[0] = error / T(mixture.sigma(used));           // Eq. (4)
    residual[1] = T(mixture.normalisation_residual(used));  // log-normaliser of Eq. (7)
    return true;
  }
};

}  // namespace

int MaxMixture::label(double error_m) const {
  // Compare -2 log p_lambda = e^2 / sigma^2 + 2 log sigma (+ shared constant).
  const double e2 = error_m * error_m;
  const double on = e2 / (sigma1_m * sigma1_m) + 2.0 * std::log(sigma1_m);
  const double off = e2 / (sigma0_m * sigma0_m) + 2.0 * std::log(sigma0_m);
  return on <= off ? 1 : 0;
}

double MaxMixture::normalisation_residual(int lambda) const {
  const double sigma_min = std::min(sigma0_m, sigma1_m);
  return std::sqrt(2.0 * std::log(sigma(lambda) / sigma_min));
}

double MaxMixture::cost(double error_m) const {
  const int lambda = label(error_m);
  const double r0 = error_m / sigma(lambda);
  const double r1 = normalisation_residual(lambda);
  return 0.5 * (r0 * r0 + r1 * r1);
}

double MaxMixture::switching_distance_m() const {
  const double s0 = sigma0_m * sigma0_m, s1 = sigma1_m * sigma1_m;
  return std::sqrt(2.0 * std::log(sigma0_m / sigma1_m) / (1.0 / s1 - 1.0 / s0));
}

ceres::CostFunction* make_surface_factor(const MeshQuery& mesh, const MaxMixture& mixture,
                                         SurfaceMode mode, double surface_offset_m,
                                         uint8_t* label_slot) {
  return new ceres::AutoDiffCostFunction<Surface, 2, kPoseBlockSize, 3>(
      new Surface{&mesh, mixture, mode, surface_offset_m, label_slot});
}

double signed_distance_to_model(const MeshQuery& mesh, const Pose3& T_world_model,
                                const Eigen::Vector3d& landmark_world) {
  return signed_distance<double>(mesh, T_world_model.inverse() * landmark_world);
}

}  // namespace keel::ba
