#include "worker/ba/prior_factors.h"

#include <ceres/autodiff_cost_function.h>

#include <cmath>

#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// Smallest signed angle equivalent to `a` (differentiable: atan2 of sin and cos).
template <typename T>
T wrap_angle(const T& a) {
  return atan2(sin(a), cos(a));
}

struct PosePrior {
  Eigen::Quaterniond q_prior;
  Eigen::Vector3d t_prior;
  double sigma_m, sigma_rad;

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    // Eq. (8): the prior's error in the tangent space of the prior.
    const Eigen::Quaternion<T> dq =
        q_prior.cast<T>().conjugate() * block_rotation(pose).normalized();
    const Vec3<T> dphi = rotation_vector(dq);
    const Vec3<T> dt = block_translation(pose) - t_prior.cast<T>();
    for (int k = 0; k < 3; ++k) {
      residual[k] = dphi[k] / T(sigma_rad);
      residual[3 + k] = dt[k] / T(sigma_m);
    }
    return true;
  }
};

struct DepthPitchRollPrior {
  DepthPitchRoll measured;
  double sigma_m, sigma_pitch, sigma_roll;

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    // Eq. (9) with R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch),
    // R(2,1) = cos(pitch) sin(roll), R(2,2) = cos(pitch) cos(roll).
    const Eigen::Matrix<T, 3, 3> R = block_rotation(pose).normalized().toRotationMatrix();
    const T roll = atan2(R(2, 1), R(2, 2));
    const T pitch = atan2(-R(2, 0), sqrt(R(2, 1) * R(2, 1) + R(2, 2) * R(2, 2)));
    residual[0] = (pose[6] - T(measured.z_world_m)) / T(sigma_m);
    residual[1] = wrap_angle(pitch - T(measured.pitch_rad)) / T(sigma_pitch);
    residual[2] = wrap_angle(roll - T(measured.roll_rad)) / T(sigma_roll);
    return true;
  }
};

struct ServoAnglePrior {
  double measured_rad, sigma_rad;

  template <typename T>
  bool operator()(const T* theta, T* residual) const {
    residual[0] = (theta[0] - T(measured_rad)) / T(sigma_rad);  // Eq. (10)
    return true;
  }
};

}  // namespace

ceres::CostFunction* make_pose_prior_factor(const Pose3& prior, double sigma_m, double sigma_rad) {
  return new ceres::AutoDiffCostFunction<PosePrior, 6, kPoseBlockSize>(
      new PosePrior{Eigen::Quaterniond(prior.linear()), prior.translation(), sigma_m, sigma_rad});
}

ceres::CostFunction* make_depth_pitch_roll_factor(const DepthPitchRoll& measured, double sigma_m,
                                                  double sigma_pitch_rad, double sigma_roll_rad) {
  return new ceres::AutoDiffCostFunction<DepthPitchRollPrior, 3, kPoseBlockSize>(
      new DepthPitchRollPrior{measured, sigma_m, sigma_pitch_rad, sigma_roll_rad});
}

ceres::CostFunction* make_servo_angle_factor(double measured_rad, double sigma_rad) {
  return new ceres::AutoDiffCostFunction<ServoAnglePrior, 1, 1>(
      new ServoAnglePrior{measured_rad, sigma_rad});
}

DepthPitchRoll depth_pitch_roll_of(const Pose3& T_world_vehicle) {
  const Eigen::Matrix3d R = T_world_vehicle.linear();
  DepthPitchRoll out;
  out.z_world_m = T_world_vehicle.translation().z();
  out.roll_rad = std::atan2(R(2, 1), R(2, 2));
  out.pitch_rad = std::atan2(-R(2, 0), std::hypot(R(2, 1), R(2, 2)));
  return out;
}

}  // namespace keel::ba
