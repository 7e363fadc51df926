#include "worker/slam/relative_pose_factor.h"

#include "worker/slam/manifolds.h"
#include "worker/slam/so3.h"

namespace keel::slam {

RelativePoseFactor::RelativePoseFactor(const Eigen::Isometry3d& T_i_j,
                                       const Eigen::Matrix<double, 6, 6>& sqrt_info)
    : R_ij_(T_i_j.linear()), t_ij_(T_i_j.translation()), sqrt_info_(sqrt_info) {}

bool RelativePoseFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const Eigen::Vector3d p_i = block_position(parameters[0]);
  const Eigen::Matrix3d R_i = block_rotation(parameters[0] + 3);
  const Eigen::Vector3d p_j = block_position(parameters[1]);
  const Eigen::Matrix3d R_j = block_rotation(parameters[1] + 3);

  const Eigen::Vector3d dp_in_i = R_i.transpose() * (p_j - p_i);
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = dp_in_i - t_ij_;
  r.tail<3>() = so3_log(R_ij_.transpose() * R_i.transpose() * R_j);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians == nullptr) return true;

  const Eigen::Matrix3d Jr_inv = right_jacobian_inverse(r.tail<3>());
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
    J.block<3, 3>(0, 0) = -R_i.transpose();
    J.block<3, 3>(0, 3) = hat(dp_in_i);
    J.block<3, 3>(3, 3) = -Jr_inv * R_j.transpose() * R_i;
    set_lifted_jacobian<6, 6, 7>(sqrt_info_ * J, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
    J.block<3, 3>(0, 0) = R_i.transpose();
    J.block<3, 3>(3, 3) = Jr_inv;
    set_lifted_jacobian<6, 6, 7>(sqrt_info_ * J, jacobians[1]);
  }
  return true;
}

}  // namespace keel::slam
