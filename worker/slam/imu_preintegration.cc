#include "worker/slam/imu_preintegration.h"

#include "worker/slam/so3.h"

namespace keel::slam {

ImuPreintegration::ImuPreintegration(const Eigen::Vector3d& bias_gyro_lin,
                                     const Eigen::Vector3d& bias_accel_lin, const ImuNoise& noise)
    : bias_gyro_lin_(bias_gyro_lin), bias_accel_lin_(bias_accel_lin), noise_(noise) {}

void ImuPreintegration::integrate(const Eigen::Vector3d& gyro_radps,
                                  const Eigen::Vector3d& accel_mps2, double dt_s) {
  const Eigen::Vector3d w = gyro_radps - bias_gyro_lin_;
  const Eigen::Vector3d a = accel_mps2 - bias_accel_lin_;
  const double dt2 = dt_s * dt_s;
  const Eigen::Matrix3d dR_step = so3_exp(w * dt_s);  // Delta R~_{k,k+1}
  const Eigen::Matrix3d Jr = right_jacobian(w * dt_s);
  const Eigen::Matrix3d R_a_hat = delta_R_ * hat(a);

  // Noise propagation, Forster Eq. (62): eta_{ik+1} = A eta_ik + B eta_k, order [phi, v, p].
  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = dR_step.transpose();
  A.block<3, 3>(3, 0) = -R_a_hat * dt_s;
  A.block<3, 3>(6, 0) = -0.5 * R_a_hat * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt_s;
  Eigen::Matrix<double, 9, 6> B = Eigen::Matrix<double, 9, 6>::Zero();
  B.block<3, 3>(0, 0) = Jr * dt_s;
  B.block<3, 3>(3, 3) = delta_R_ * dt_s;
  B.block<3, 3>(6, 3) = 0.5 * delta_R_ * dt2;
  // Discrete-time noise: Cov(eta_d) = Cov(eta) / dt (Forster Sec. IV-A).
  Eigen::Matrix<double, 6, 6> Q = Eigen::Matrix<double, 6, 6>::Zero();
  Q.diagonal().head<3>().setConstant(noise_.gyro_noise_density * noise_.gyro_noise_density / dt_s);
  Q.diagonal().tail<3>().setConstant(noise_.accel_noise_density * noise_.accel_noise_density /
                                     dt_s);
  covariance_ = A * covariance_ * A.transpose() + B * Q * B.transpose();

  // Bias Jacobians, Forster App. B (recursive form); p and v use the values at step k.
  dp_dba_ += dv_dba_ * dt_s - 0.5 * delta_R_ * dt2;
  dp_dbg_ += dv_dbg_ * dt_s - 0.5 * R_a_hat * dR_dbg_ * dt2;
  dv_dba_ -= delta_R_ * dt_s;
  dv_dbg_ -= R_a_hat * dR_dbg_ * dt_s;
  dR_dbg_ = dR_step.transpose() * dR_dbg_ - Jr * dt_s;

  // Means, Forster Eq. (24)-(26) in incremental form.
  delta_p_ += delta_v_ * dt_s + 0.5 * delta_R_ * a * dt2;
  delta_v_ += delta_R_ * a * dt_s;
  delta_R_ = delta_R_ * dR_step;
  dt_s_ += dt_s;
}

Eigen::Matrix3d ImuPreintegration::corrected_delta_R(const Eigen::Vector3d& bias_gyro) const {
  return delta_R_ * so3_exp(dR_dbg_ * (bias_gyro - bias_gyro_lin_));
}

Eigen::Vector3d ImuPreintegration::corrected_delta_v(const Eigen::Vector3d& bias_gyro,
                                                     const Eigen::Vector3d& bias_accel) const {
  return delta_v_ + dv_dbg_ * (bias_gyro - bias_gyro_lin_) +
         dv_dba_ * (bias_accel - bias_accel_lin_);
}

Eigen::Vector3d ImuPreintegration::corrected_delta_p(const Eigen::Vector3d& bias_gyro,
                                                     const Eigen::Vector3d& bias_accel) const {
  return delta_p_ + dp_dbg_ * (bias_gyro - bias_gyro_lin_) +
         dp_dba_ * (bias_accel - bias_accel_lin_);
}

}  // namespace keel::slam
