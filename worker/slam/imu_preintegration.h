// On-manifold IMU preintegration between two keyframes, seed 000 ref. [27] (Forster et al.,
// "On-manifold preintegration for real-time visual-inertial odometry", T-RO 2017), with the
// bias Jacobians of its Eq. (44)/App. B and the covariance of its Eq. (62)-(63).
#pragma once

#include <Eigen/Core>

namespace keel::slam {

// Continuous-time noise figures; defaults are seed 000 Table I (Xsens MTi-30).
struct ImuNoise {
  double gyro_noise_density = 5.7e-4;   // rad/s/sqrt(Hz)
  double accel_noise_density = 9.4e-4;  // m/s^2/sqrt(Hz)
  double gyro_random_walk = 3.7e-6;     // rad/s^2/sqrt(Hz)
  double accel_random_walk = 2.4e-6;    // m/s^3/sqrt(Hz)
};

// Preintegrated measurements Delta R~_ij, Delta v~_ij, Delta p~_ij at the linearisation biases
// (bg_lin, ba_lin), their Jacobians w.r.t. the biases, and the 9x9 covariance of the
// preintegration noise [delta phi, delta v, delta p] (Forster Eq. (38), (62)).
class ImuPreintegration {
 public:
  using Matrix9d = Eigen::Matrix<double, 9, 9>;

  ImuPreintegration(const Eigen::Vector3d& bias_gyro_lin, const Eigen::Vector3d& bias_accel_lin,
                    const ImuNoise& noise);

  // Adds one sample held over dt_s (Forster Eq. (24)-(26) for the means, (62) for the noise,
  // App. B for the bias Jacobians).
  void integrate(const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& accel_mps2, double dt_s);

  double dt_s() const { return dt_s_; }
  const Eigen::Matrix3d& delta_R() const { return delta_R_; }
  const Eigen::Vector3d& delta_v() const { return delta_v_; }
  const Eigen::Vector3d& delta_p() const { return delta_p_; }
  const Matrix9d& covariance() const { return covariance_; }  // [phi, v, p]
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }
  const Eigen::Vector3d& bias_gyro_lin() const { return bias_gyro_lin_; }
  const Eigen::Vector3d& bias_accel_lin() const { return bias_accel_lin_; }

  // First-order bias update, Forster Eq. (44).
  Eigen::Matrix3d corrected_delta_R(const Eigen::Vector3d& bias_gyro) const;
  Eigen::Vector3d corrected_delta_v(const Eigen::Vector3d& bias_gyro,
                                    const Eigen::Vector3d& bias_accel) const;
  Eigen::Vector3d corrected_delta_p(const Eigen::Vector3d& bias_gyro,
                                    const Eigen::Vector3d& bias_accel) const;

 private:
  Eigen::Vector3d bias_gyro_lin_, bias_accel_lin_;
  ImuNoise noise_;
  double dt_s_ = 0.0;
  Eigen::Matrix3d delta_R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d delta_v_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_p_ = Eigen::Vector3d::Zero();
  Matrix9d covariance_ = Matrix9d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
};

}  // namespace keel::slam
