#include "worker/slam/dvl_factor.h"

#include "worker/slam/manifolds.h"
#include "worker/slam/so3.h"

namespace keel::slam {

DvlFactor::DvlFactor(std::shared_ptr<const DvlPreintegration> preintegration,
                     const Eigen::Vector3d& t_imu_dvl, const Eigen::Matrix3d& sqrt_info)
    : pre_(std::move(preintegration)), t_(t_imu_dvl), sqrt_info_(sqrt_info) {}

bool DvlFactor::Evaluate(double const* const* parameters, double* residuals,
                         double** jacobians) const {
  const Eigen::Vector3d p_i = block_position(parameters[0]);
  const Eigen::Matrix3d R_i = block_rotation(parameters[0] + 3);
  const Eigen::Map<const Eigen::Vector3d> bg(parameters[1]);
  const Eigen::Map<const Eigen::Vector3d> bv(parameters[2]);
  const Eigen::Vector3d p_j = block_position(parameters[3]);
  const Eigen::Matrix3d R_j = block_rotation(parameters[3] + 3);
  const double s = parameters[4][0];
  const Eigen::Matrix3d R_imu_dvl = block_rotation(parameters[5]);

  const Eigen::Matrix3d Rt = R_i.transpose();
  const Eigen::Vector3d dp_pred = pre_->corrected_delta_p(bg, bv, s, R_imu_dvl);
  const Eigen::Vector3d r =
      Rt * (p_j - p_i) + (Rt * R_j - Eigen::Matrix3d::Identity()) * t_ - dp_pred;  // Eq. (15)
  Eigen::Map<Eigen::Vector3d> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians == nullptr) return true;

  const double ratio = pre_->scale_lin() / s;
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  using RowMat33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {  // pose_i
    Mat36 J;
    J.leftCols<3>() = -Rt;
    J.rightCols<3>() = hat(Rt * (p_j - p_i + R_j * t_));
    set_lifted_jacobian<3, 6, 7>(sqrt_info_ * J, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {  // b^w_i: Eq. (27)-(28)
    Eigen::Map<RowMat33> j1_out(jacobians[1]);
    j1_out = sqrt_info_ * (-ratio * pre_->dp_dbg());
  }
  if (jacobians[2] != nullptr) {  // b^v_i: Eq. (27), (29)
    Eigen::Map<RowMat33> j2_out(jacobians[2]);
    j2_out = sqrt_info_ * (-ratio * pre_->dp_dbv());
  }
  if (jacobians[3] != nullptr) {  // pose_j
    Mat36 J;
    J.leftCols<3>() = Rt;
    J.rightCols<3>() = -Rt * R_j * hat(t_);
    set_lifted_jacobian<3, 6, 7>(sqrt_info_ * J, jacobians[3]);
  }
  if (jacobians[4] != nullptr) {  // s_d: d/ds (s_lin / s) x = -(1/s) (s_lin / s) x
    Eigen::Map<Eigen::Vector3d> j4_out(jacobians[4]);
    j4_out = sqrt_info_ * (dp_pred / s);
  }
  if (jacobians[5] != nullptr) {  // R_B,Bo <- R_B,Bo Exp(theta)
    const Eigen::Vector3d d_theta = so3_log(pre_->R_imu_dvl_lin().transpose() * R_imu_dvl);
    const Eigen::Matrix3d J = -ratio * pre_->dp_dtheta() * right_jacobian_inverse(d_theta);
    set_lifted_jacobian<3, 3, 4>(sqrt_info_ * J, jacobians[5]);
  }
  return true;
}

}  // namespace keel::slam
