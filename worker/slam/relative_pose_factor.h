// Relative-pose factor for odometry (L_ij) and loop closures (L_pq) of Eq. (3), seed 000:
//   r = [ R_i^T (p_j - p_i) - t_ij ;  Log(R_ij^T R_i^T R_j) ]     (6, translation first)
// where (R_ij, t_ij) = T_i_j is the measured relative pose, whose noise is
// t = t_ij + delta t, R = R_ij Exp(delta phi); information in that [t, phi] order.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keel::slam {

class RelativePoseFactor : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  RelativePoseFactor(const Eigen::Isometry3d& T_i_j, const Eigen::Matrix<double, 6, 6>& sqrt_info);
  // Parameters: pose_i, pose_j (manifolds.h layout).
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d R_ij_;
  Eigen::Vector3d t_ij_;
  Eigen::Matrix<double, 6, 6> sqrt_info_;
};

}  // namespace keel::slam
