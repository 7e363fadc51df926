// DVL preintegration: the preintegrated relative position of Eq. (11), seed 000, from
// pseudosensor measurements (IMU gyro + interpolated DVL velocity, Algorithm 1), with
//  - the noise propagation of Eq. (16) using A and B of Eq. (31)-(32) (Appendix B),
//  - the first-order bias correction of Eq. (27)-(29) (Appendix A),
//  - beyond the paper (its Sec. VII): the exact dependence on the scale factor s_d (Eq. (11)
//    is linear in 1/s_d) and a first-order correction for the DVL-IMU extrinsic rotation,
//    so both can be estimated as states.
#pragma once

#include <Eigen/Core>

namespace keel::slam {

// DVL noise. Defaults are seed 000 Sec. V-B / Table I (Water Linked DVL A50): white noise
// sigma = 1e-3 |v~| and bias random walk 1e-4 |v~|. The paper scales both with the measured
// velocity, which makes them vanish at rest; a floor keeps the information finite there
// (engineering choice, not in the paper).
struct DvlNoise {
  double velocity_sigma_rel = 1.0e-3;        // sigma_v = velocity_sigma_rel * |v~|   [-]
  double velocity_sigma_floor_mps = 5.0e-4;  // combined in quadrature                 [m/s]
  double bias_random_walk_rel = 1.0e-4;      // sigma_bv = rel * |v~|  [m/s/sqrt(Hz) per m/s]
  double bias_random_walk_floor = 1.0e-5;    // combined in quadrature  [m/s/sqrt(Hz)]

  // Per-sample white-noise sigma of one DVL measurement with speed |v~| (m/s).
  double velocity_sigma(double speed_mps) const;
  // Random-walk density of b^v at speed |v~| (m/s/sqrt(Hz)), Eq. (6)-(7).
  double bias_random_walk(double speed_mps) const;
};

class DvlPreintegration {
 public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  // Linearisation point: biases b^w, b^v (b^v in the IMU frame B, as Eq. (11) subtracts it
  // from the velocity already rotated into B), scale s_d and extrinsic rotation R_B,Bo.
  DvlPreintegration(const Eigen::Vector3d& bias_gyro_lin, const Eigen::Vector3d& bias_vel_lin,
                    double scale_lin, const Eigen::Matrix3d& R_imu_dvl_lin, const DvlNoise& noise,
                    double gyro_noise_density);

  // Adds one pseudosensor measurement (gyro in B, interpolated DVL velocity in B_o) held over
  // dt_s. dvl_period_s is the spacing of the DVL samples it was interpolated from: the DVL's
  // white noise has per-sample sigma_v, i.e. a density sigma_v^2 * dvl_period_s, which at the
  // pseudo (IMU) rate is the discrete covariance sigma_v^2 * dvl_period_s / dt_s. (Eq. (16)
  // leaves Sigma_eta unspecified; this keeps the integrated noise independent of the IMU rate.)
  void integrate(const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& velocity_dvl_mps,
                 double dt_s, double dvl_period_s);

  double dt_s() const { return dt_s_; }
  double mean_speed_mps() const { return dt_s_ > 0 ? speed_integral_ / dt_s_ : 0.0; }
  const Eigen::Matrix3d& delta_R() const { return delta_R_; }  // Eq. (13)
  const Eigen::Vector3d& delta_p() const { return delta_p_; }  // Eq. (11)
  const Matrix6d& covariance() const { return covariance_; }   // Eq. (16), order [phi, p]
  Eigen::Matrix3d position_covariance() const { return covariance_.block<3, 3>(3, 3); }
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }        // Eq. (28)
  const Eigen::Matrix3d& dp_dbv() const { return dp_dbv_; }        // Eq. (29)
  const Eigen::Matrix3d& dp_dtheta() const { return dp_dtheta_; }  // R_B,Bo <- R Exp(theta)
  const Eigen::Vector3d& bias_gyro_lin() const { return bias_gyro_lin_; }
  const Eigen::Vector3d& bias_vel_lin() const { return bias_vel_lin_; }
  double scale_lin() const { return scale_lin_; }
  const Eigen::Matrix3d& R_imu_dvl_lin() const { return R_imu_dvl_lin_; }

  // Delta p~_ij(b^w, b^v, s_d, R_B,Bo): Eq. (27) for the biases, first order in the extrinsic
  // rotation, exact in s_d (Eq. (11) is the linearisation-point sum times s_lin / s_d).
  Eigen::Vector3d corrected_delta_p(const Eigen::Vector3d& bias_gyro,
                                    const Eigen::Vector3d& bias_vel, double scale,
                                    const Eigen::Matrix3d& R_imu_dvl) const;

 private:
  Eigen::Vector3d bias_gyro_lin_, bias_vel_lin_;
  double scale_lin_;
  Eigen::Matrix3d R_imu_dvl_lin_;
  DvlNoise noise_;
  double gyro_noise_density_;
  double dt_s_ = 0.0;
  double speed_integral_ = 0.0;
  Eigen::Matrix3d delta_R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d delta_p_ = Eigen::Vector3d::Zero();
  Matrix6d covariance_ = Matrix6d::Zero();  // Sigma_D_ii = 0 (Appendix B)
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbv_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dtheta_ = Eigen::Matrix3d::Zero();
};

}  // namespace keel::slam
