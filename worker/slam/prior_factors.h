// Prior factors r_0 of Eq. (3), seed 000 (the robot's initial state), and priors on the
// calibration states estimated beyond the paper.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keel::slam {

// r = [p - p_prior; Log(R_prior^T R)], order [translation, rotation].
class PosePriorFactor : public ceres::SizedCostFunction<6, 7> {
 public:
  PosePriorFactor(const Eigen::Isometry3d& T_prior, const Eigen::Matrix<double, 6, 6>& sqrt_info);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d R_;
  Eigen::Vector3d p_;
  Eigen::Matrix<double, 6, 6> sqrt_info_;
};

// A MAP anchor (beyond the paper): the online SLAM's recorded pose of a keyframe, whose position
// error is white noise plus a drift d that random-walks along the path (the online system dead
// reckons along what its scan matching cannot see). r = [p - p_map - d; Log(R_map^T R)], order
// [translation (world), rotation (body)], on a pose block and the keyframe's drift state d.
class MapAnchorFactor : public ceres::SizedCostFunction<6, 7, 3> {
 public:
  MapAnchorFactor(const Eigen::Isometry3d& T_map, const Eigen::Matrix<double, 6, 6>& sqrt_info);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d R_;
  Eigen::Vector3d p_;
  Eigen::Matrix<double, 6, 6> sqrt_info_;
};

// Random walk of a 3-vector with a full covariance: r = S (x_j - x_i), S^T S = Q^-1 (the MAP
// drift between consecutive keyframes, Q = drift covariance per metre times the path length).
class VectorRandomWalkFactor : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  explicit VectorRandomWalkFactor(const Eigen::Matrix3d& sqrt_info);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d sqrt_info_;
};

// r = Log(R_prior^T R) on a rotation block (e.g. the DVL-IMU extrinsic).
class RotationPriorFactor : public ceres::SizedCostFunction<3, 4> {
 public:
  RotationPriorFactor(const Eigen::Matrix3d& R_prior, const Eigen::Matrix3d& sqrt_info);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d R_;
  Eigen::Matrix3d sqrt_info_;
};

// Bias random walk, Eq. (6)-(7): r = (b_j - b_i) / (sigma sqrt(dt_ij)), for b^w, b^a and b^v.
class BiasRandomWalkFactor : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  // random_walk_density: sigma of eta^b (units/s/sqrt(Hz) of the bias), dt_s = t_j - t_i.
  BiasRandomWalkFactor(double random_walk_density, double dt_s);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double weight_;
};

}  // namespace keel::slam
