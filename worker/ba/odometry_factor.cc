#include "worker/ba/odometry_factor.h"

#include <ceres/autodiff_cost_function.h>

#include <algorithm>
#include <stdexcept>

#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

struct Odometry {
  Eigen::Quaterniond q_ij;
  Eigen::Vector3d t_ij;
  OdometrySigmas sigmas;

  template <typename T>
  bool operator()(const T* pose_i, const T* pose_j, T* residual) const {
    // Eq. (11): predicted relative pose (-)x_gi (+) x_gj = (R_i^T R_j, R_i^T (t_j - t_i)).
    const Eigen::Quaternion<T> q_i = block_rotation(pose_i).normalized();
    const Eigen::Quaternion<T> q_j = block_rotation(pose_j).normalized();
    const Eigen::Quaternion<T> q_pred = q_i.conjugate() * q_j;
    const Vec3<T> t_pred =
        q_i.conjugate() * (block_translation(pose_j) - block_translation(pose_i));
    // Error in the measurement's frame: E = measured^-1 * predicted.
    const Eigen::Quaternion<T> q_meas_inv = q_ij.cast<T>().conjugate();
    const Vec3<T> dphi = rotation_vector(q_meas_inv * q_pred);
    const Vec3<T> dt = q_meas_inv * (t_pred - t_ij.cast<T>());
    for (int k = 0; k < 3; ++k) {
      residual[k] = dphi[k] / T(sigmas.sigma_rad);
      residual[3 + k] = dt[k] / T(sigmas.sigma_m);
    }
    return true;
  }
};

}  // namespace

OdometrySigmas odometry_sigmas(double dt_s, double sigma_m_per_s, double sigma_rad_per_s,
                               double min_sigma_m, double min_sigma_rad) {
  if (!(dt_s > 0)) {
    throw std::invalid_argument("odometry: keyframe time difference must be > 0 s, got " +
                                std::to_string(dt_s));
  }
  return {std::max(sigma_m_per_s * dt_s, min_sigma_m),
          std::max(sigma_rad_per_s * dt_s, min_sigma_rad)};
}

ceres::CostFunction* make_odometry_factor(const Pose3& T_i_j_measured,
                                          const OdometrySigmas& sigmas) {
  return new ceres::AutoDiffCostFunction<Odometry, 6, kPoseBlockSize, kPoseBlockSize>(new Odometry{
      Eigen::Quaterniond(T_i_j_measured.linear()), T_i_j_measured.translation(), sigmas});
}

}  // namespace keel::ba
