#include "worker/slam/dvl_preintegration.h"

#include <cmath>

#include "worker/slam/so3.h"

namespace keel::slam {

double DvlNoise::velocity_sigma(double speed_mps) const {
  return std::hypot(velocity_sigma_floor_mps, velocity_sigma_rel * speed_mps);
}

double DvlNoise::bias_random_walk(double speed_mps) const {
  return std::hypot(bias_random_walk_floor, bias_random_walk_rel * speed_mps);
}

DvlPreintegration::DvlPreintegration(const Eigen::Vector3d& bias_gyro_lin,
                                     const Eigen::Vector3d& bias_vel_lin, double scale_lin,
                                     const Eigen::Matrix3d& R_imu_dvl_lin, const DvlNoise& noise,
                                     double gyro_noise_density)
    : bias_gyro_lin_(bias_gyro_lin),
      bias_vel_lin_(bias_vel_lin),
      scale_lin_(scale_lin),
      R_imu_dvl_lin_(R_imu_dvl_lin),
      noise_(noise),
      gyro_noise_density_(gyro_noise_density) {}

void DvlPreintegration::integrate(const Eigen::Vector3d& gyro_radps,
                                  const Eigen::Vector3d& velocity_dvl_mps, double dt_s,
                                  double dvl_period_s) {
  const double inv_s = 1.0 / scale_lin_;
  const Eigen::Vector3d w_dt = (gyro_radps - bias_gyro_lin_) * dt_s;   // Eq. (13) increment
  const Eigen::Matrix3d dR_step = so3_exp(w_dt);                       // Delta R~_{k,k+1}
  const Eigen::Matrix3d Jr = right_jacobian(w_dt);                     // J_r^k of Eq. (14)
  const Eigen::Vector3d v_imu = R_imu_dvl_lin_ * velocity_dvl_mps;     // B~v_k (Eq. (19))
  const Eigen::Vector3d v_unbiased = (v_imu - bias_vel_lin_) * inv_s;  // (v~_k - b^v) / s_d
  const Eigen::Matrix3d v_hat = hat(v_unbiased);

  // Eq. (31)-(32): [dphi; dp]_{k+1} = A [dphi; dp]_k + B [eta^w; eta^v].
  // Eq. (30)-(31) print B's lower block as Delta R~_ik dt, but Eq. (12), from which they are
  // derived, has eta^v / s_d; the 1/s_d is kept here so (16) is the covariance of (12).
  Matrix6d A = Matrix6d::Identity();
  A.block<3, 3>(0, 0) = dR_step.transpose();
  A.block<3, 3>(3, 0) = -delta_R_ * v_hat * dt_s;
  Matrix6d B = Matrix6d::Zero();
  B.block<3, 3>(0, 0) = Jr * dt_s;
  B.block<3, 3>(3, 3) = delta_R_ * dt_s * inv_s;
  // Sigma_eta^D: gyro as in [27] (density^2 / dt), DVL per the header comment.
  const double sigma_v = noise_.velocity_sigma(velocity_dvl_mps.norm());
  Matrix6d Q = Matrix6d::Zero();
  Q.diagonal().head<3>().setConstant(gyro_noise_density_ * gyro_noise_density_ / dt_s);
  Q.diagonal().tail<3>().setConstant(sigma_v * sigma_v * dvl_period_s / dt_s);
  covariance_ = A * covariance_ * A.transpose() + B * Q * B.transpose();  // Eq. (16)

  // Bias Jacobians, Eq. (28)-(29), accumulated term by term (they use Delta R~_ik, i.e. the
  // values before this step's rotation update).
  dp_dbg_ -= delta_R_ * v_hat * dR_dbg_ * dt_s;
  dp_dbv_ -= delta_R_ * dt_s * inv_s;
  // Extrinsic: R_B,Bo Exp(theta) v_o ~= R_B,Bo v_o - R_B,Bo (v_o)^ theta.
  dp_dtheta_ -= delta_R_ * R_imu_dvl_lin_ * hat(velocity_dvl_mps) * dt_s * inv_s;
  dR_dbg_ = dR_step.transpose() * dR_dbg_ - Jr * dt_s;  // [27], App. B

  delta_p_ += delta_R_ * v_unbiased * dt_s;  // Eq. (11), one term of the sum
  delta_R_ = delta_R_ * dR_step;             // Eq. (13)
  dt_s_ += dt_s;
  speed_integral_ += velocity_dvl_mps.norm() * dt_s;
}

Eigen::Vector3d DvlPreintegration::corrected_delta_p(const Eigen::Vector3d& bias_gyro,
                                                     const Eigen::Vector3d& bias_vel, double scale,
                                                     const Eigen::Matrix3d& R_imu_dvl) const {
  const Eigen::Vector3d d_theta = so3_log(R_imu_dvl_lin_.transpose() * R_imu_dvl);
  const Eigen::Vector3d at_lin_scale = delta_p_ + dp_dbg_ * (bias_gyro - bias_gyro_lin_) +
                                       dp_dbv_ * (bias_vel - bias_vel_lin_) +
                                       dp_dtheta_ * d_theta;  // Eq. (27)
  return (scale_lin_ / scale) * at_lin_scale;
}

}  // namespace keel::slam
