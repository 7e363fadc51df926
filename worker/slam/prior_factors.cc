#include "worker/slam/prior_factors.h"

#include <cmath>

#include "worker/slam/manifolds.h"
#include "worker/slam/so3.h"

namespace keel::slam {

PosePriorFactor::PosePriorFactor(const Eigen::Isometry3d& T_prior,
                                 const Eigen::Matrix<double, 6, 6>& sqrt_info)
    : R_(T_prior.linear()), p_(T_prior.translation()), sqrt_info_(sqrt_info) {}

bool PosePriorFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const Eigen::Vector3d p = block_position(parameters[0]);
  const Eigen::Matrix3d R = block_rotation(parameters[0] + 3);
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = p - p_;
  r.tail<3>() = so3_log(R_.transpose() * R);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Identity();
    J.block<3, 3>(3, 3) = right_jacobian_inverse(r.tail<3>());
    set_lifted_jacobian<6, 6, 7>(sqrt_info_ * J, jacobians[0]);
  }
  return true;
}

MapAnchorFactor::MapAnchorFactor(const Eigen::Isometry3d& T_map,
                                 const Eigen::Matrix<double, 6, 6>& sqrt_info)
    : R_(T_map.linear()), p_(T_map.translation()), sqrt_info_(sqrt_info) {}

bool MapAnchorFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const Eigen::Vector3d p = block_position(parameters[0]);
  const Eigen::Matrix3d R = block_rotation(parameters[0] + 3);
  const Eigen::Map<const Eigen::Vector3d> drift(parameters[1]);
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = p - p_ - drift;
  r.tail<3>() = so3_log(R_.transpose() * R);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians == nullptr) return true;
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Identity();
    J.block<3, 3>(3, 3) = right_jacobian_inverse(r.tail<3>());
    set_lifted_jacobian<6, 6, 7>(sqrt_info_ * J, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>> j1_out(jacobians[1]);
    j1_out = -sqrt_info_.leftCols<3>();
  }
  return true;
}

VectorRandomWalkFactor::VectorRandomWalkFactor(const Eigen::Matrix3d& sqrt_info)
    : sqrt_info_(sqrt_info) {}

bool VectorRandomWalkFactor::Evaluate(double const* const* parameters, double* residuals,
                                      double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> x_i(parameters[0]), x_j(parameters[1]);
  Eigen::Map<Eigen::Vector3d> residual_out(residuals);
  residual_out = sqrt_info_ * (x_j - x_i);
  if (jacobians == nullptr) return true;
  using RowMat33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {
    Eigen::Map<RowMat33> j0_out(jacobians[0]);
    j0_out = -sqrt_info_;
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<RowMat33> j1_out(jacobians[1]);
    j1_out = sqrt_info_;
  }
  return true;
}

RotationPriorFactor::RotationPriorFactor(const Eigen::Matrix3d& R_prior,
                                         const Eigen::Matrix3d& sqrt_info)
    : R_(R_prior), sqrt_info_(sqrt_info) {}

bool RotationPriorFactor::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const Eigen::Vector3d r = so3_log(R_.transpose() * block_rotation(parameters[0]));
  Eigen::Map<Eigen::Vector3d> residual_out(residuals);
  residual_out = sqrt_info_ * r;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    set_lifted_jacobian<3, 3, 4>(sqrt_info_ * right_jacobian_inverse(r), jacobians[0]);
  }
  return true;
}

BiasRandomWalkFactor::BiasRandomWalkFactor(double random_walk_density, double dt_s)
    : weight_(1.0 / (random_walk_density * std::sqrt(dt_s))) {}

bool BiasRandomWalkFactor::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  for (int k = 0; k < 3; ++k) residuals[k] = weight_ * (parameters[1][k] - parameters[0][k]);
  if (jacobians == nullptr) return true;
  using RowMat33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {
    Eigen::Map<RowMat33> j0_out(jacobians[0]);
    j0_out = -weight_ * Eigen::Matrix3d::Identity();
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<RowMat33> j1_out(jacobians[1]);
    j1_out = weight_ * Eigen::Matrix3d::Identity();
  }
  return true;
}

}  // namespace keel::slam
