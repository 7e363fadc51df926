#include "worker/slam/imu_factor.h"

#include "worker/slam/information.h"
#include "worker/slam/manifolds.h"
#include "worker/slam/so3.h"

namespace keel::slam {

ImuFactor::ImuFactor(std::shared_ptr<const ImuPreintegration> preintegration,
                     const Eigen::Vector3d& gravity_world, const Matrix9d& sqrt_info)
    : pre_(std::move(preintegration)), g_(gravity_world), sqrt_info_(sqrt_info) {}

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals,
                         double** jacobians) const {
  const Eigen::Vector3d p_i = block_position(parameters[0]);
  const Eigen::Matrix3d R_i = block_rotation(parameters[0] + 3);
  const Eigen::Map<const Eigen::Vector3d> v_i(parameters[1]);
  const Eigen::Map<const Eigen::Vector3d> bg(parameters[2]);
  const Eigen::Map<const Eigen::Vector3d> ba(parameters[3]);
  const Eigen::Vector3d p_j = block_position(parameters[4]);
  const Eigen::Matrix3d R_j = block_rotation(parameters[4] + 3);
  const Eigen::Map<const Eigen::Vector3d> v_j(parameters[5]);
  const double dt = pre_->dt_s();

  const Eigen::Vector3d dbg = bg - pre_->bias_gyro_lin();
  const Eigen::Vector3d phi_bg = pre_->dR_dbg() * dbg;
  const Eigen::Matrix3d dR_corr = pre_->delta_R() * so3_exp(phi_bg);
  const Eigen::Vector3d dv_world = v_j - v_i - g_ * dt;
  const Eigen::Vector3d dp_world = p_j - p_i - v_i * dt - 0.5 * g_ * dt * dt;

  Eigen::Matrix<double, 9, 1> r;
  r.segment<3>(0) = so3_log(dR_corr.transpose() * R_i.transpose() * R_j);
  r.segment<3>(3) = R_i.transpose() * dv_world - pre_->corrected_delta_v(bg, ba);
  r.segment<3>(6) = R_i.transpose() * dp_world - pre_->corrected_delta_p(bg, ba);
  Eigen::Map<Eigen::Matrix<double, 9, 1>> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians == nullptr) return true;

  const Eigen::Vector3d r_R = r.segment<3>(0);
  const Eigen::Matrix3d Jr_inv = right_jacobian_inverse(r_R);
  const Eigen::Matrix3d Rt = R_i.transpose();
  using Mat96 = Eigen::Matrix<double, 9, 6>;
  using Mat93 = Eigen::Matrix<double, 9, 3>;
  if (jacobians[0] != nullptr) {  // pose_i, [27] App. C
    Mat96 J = Mat96::Zero();
    J.block<3, 3>(0, 3) = -Jr_inv * R_j.transpose() * R_i;
    J.block<3, 3>(3, 3) = hat(Rt * dv_world);
    J.block<3, 3>(6, 0) = -Rt;
    J.block<3, 3>(6, 3) = hat(Rt * dp_world);
    set_lifted_jacobian<9, 6, 7>(sqrt_info_ * J, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {  // v_i
    Mat93 J = Mat93::Zero();
    J.block<3, 3>(3, 0) = -Rt;
    J.block<3, 3>(6, 0) = -Rt * dt;
    Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> j1_out(jacobians[1]);
    j1_out = sqrt_info_ * J;
  }
  if (jacobians[2] != nullptr) {  // b^w_i
    Mat93 J = Mat93::Zero();
    J.block<3, 3>(0, 0) =
        -Jr_inv * so3_exp(r_R).transpose() * right_jacobian(phi_bg) * pre_->dR_dbg();
    J.block<3, 3>(3, 0) = -pre_->dv_dbg();
    J.block<3, 3>(6, 0) = -pre_->dp_dbg();
    Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> j2_out(jacobians[2]);
    j2_out = sqrt_info_ * J;
  }
  if (jacobians[3] != nullptr) {  // b^a_i
    Mat93 J = Mat93::Zero();
    J.block<3, 3>(3, 0) = -pre_->dv_dba();
    J.block<3, 3>(6, 0) = -pre_->dp_dba();
    Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> j3_out(jacobians[3]);
    j3_out = sqrt_info_ * J;
  }
  if (jacobians[4] != nullptr) {  // pose_j
    Mat96 J = Mat96::Zero();
    J.block<3, 3>(0, 3) = Jr_inv;
    J.block<3, 3>(6, 0) = Rt;
    set_lifted_jacobian<9, 6, 7>(sqrt_info_ * J, jacobians[4]);
  }
  if (jacobians[5] != nullptr) {  // v_j
    Mat93 J = Mat93::Zero();
    J.block<3, 3>(3, 0) = Rt;
    Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> j5_out(jacobians[5]);
    j5_out = sqrt_info_ * J;
  }
  return true;
}

ImuFactor::Matrix9d imu_sqrt_information(const ImuPreintegration& preintegration,
                                         bool use_position) {
  const ImuPreintegration::Matrix9d& cov = preintegration.covariance();
  ImuFactor::Matrix9d S = ImuFactor::Matrix9d::Zero();
  if (use_position) {
    S = sqrt_information_from_covariance(cov);
  } else {
    // Marginal of [phi, v]: the top-left block of the covariance.
    S.topLeftCorner<6, 6>() = sqrt_information_from_covariance(cov.topLeftCorner<6, 6>());
  }
  return S;
}

}  // namespace keel::slam
