// DVL preintegration factor D_ij, seed 000 Eq. (15): the position-only residual
//   r = R_i^T (p_j - p_i) + (R_i^T R_j - I) t_B,Bo - Delta p~_ij(b^w_i, b^v_i, s_d, R_B,Bo)
// weighted by the position block of Sigma^D_ij (Eq. (16)); rotation residuals are excluded to
// avoid double counting the gyro (Sec. IV-A). The lever-arm term is not in the paper, whose
// DVL and IMU frames coincide (Fig. 2, t = 0 gives Eq. (15) exactly): the DVL measures the
// velocity of its own origin o = p + R t, and sum_k Delta R_ik v_o,k dt = R_i^T (o_j - o_i).
// Beyond the paper, s_d and R_B,Bo are parameters (Sec. VII future work); hold them constant in
// the problem to recover the paper's known-constant assumptions (Sec. V).
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include <memory>

#include "worker/slam/dvl_preintegration.h"

namespace keel::slam {

class DvlFactor : public ceres::SizedCostFunction<3, 7, 3, 3, 7, 1, 4> {
 public:
  // t_imu_dvl: position of the DVL origin in the IMU frame (lever arm, fixed).
  DvlFactor(std::shared_ptr<const DvlPreintegration> preintegration,
            const Eigen::Vector3d& t_imu_dvl, const Eigen::Matrix3d& sqrt_info);

  // Parameters: pose_i, b^w_i, b^v_i, pose_j, s_d, q_imu_dvl (rotation block, xyzw).
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::shared_ptr<const DvlPreintegration> pre_;
  Eigen::Vector3d t_;
  Eigen::Matrix3d sqrt_info_;
};

}  // namespace keel::slam
