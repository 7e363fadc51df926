// IMU preintegration factor I_ij of Eq. (3), seed 000, as in its ref. [27] (Forster et al.,
// Eq. (45)), with the first-order bias update of [27] Eq. (44):
//   r_R = Log( (Delta R~ Exp(dR/dbg dbg))^T R_i^T R_j )
//   r_v = R_i^T (v_j - v_i - g dt) - (Delta v~ + dv/dbg dbg + dv/dba dba)
//   r_p = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2) - (Delta p~ + dp/dbg dbg + dp/dba dba)
// Residual order [r_R, r_v, r_p], matching the preintegration covariance.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include <memory>

#include "worker/slam/imu_preintegration.h"

namespace keel::slam {

class ImuFactor : public ceres::SizedCostFunction<9, 7, 3, 3, 3, 7, 3> {
 public:
  using Matrix9d = Eigen::Matrix<double, 9, 9>;

  // gravity_world: e.g. (0, 0, -9.81). sqrt_info: see imu_sqrt_information().
  ImuFactor(std::shared_ptr<const ImuPreintegration> preintegration,
            const Eigen::Vector3d& gravity_world, const Matrix9d& sqrt_info);

  // Parameters: pose_i, v_i, b^w_i, b^a_i, pose_j, v_j (velocities in the world frame).
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::shared_ptr<const ImuPreintegration> pre_;
  Eigen::Vector3d g_;
  Matrix9d sqrt_info_;
};

// Square-root information of the preintegration covariance. With use_position = false the
// position residual carries no weight (the rows are zero and [r_R, r_v] keep their marginal
// information): seed 000 Sec. IV-B sets the IMU factor's position residuals to zero where a DVL
// factor constrains the relative position.
ImuFactor::Matrix9d imu_sqrt_information(const ImuPreintegration& preintegration,
                                         bool use_position);

}  // namespace keel::slam
