#include "worker/slam/manifolds.h"

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

void store_quaternion(const Eigen::Matrix3d& R, double* q_xyzw) {
  Eigen::Quaterniond q(R);
  q.normalize();
  q_xyzw[0] = q.x();
  q_xyzw[1] = q.y();
  q_xyzw[2] = q.z();
  q_xyzw[3] = q.w();
}

}  // namespace

void set_pose_block(const Eigen::Isometry3d& T, double* pose) {
  pose[0] = T.translation().x();
  pose[1] = T.translation().y();
  pose[2] = T.translation().z();
  store_quaternion(T.linear(), pose + 3);
}

Eigen::Isometry3d get_pose_block(const double* pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = block_rotation(pose + 3);
  T.translation() = block_position(pose);
  return T;
}

void set_rotation_block(const Eigen::Matrix3d& R, double* quaternion_xyzw) {
  store_quaternion(R, quaternion_xyzw);
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  for (int k = 0; k < 3; ++k) x_plus_delta[k] = x[k] + delta[k];
  const Eigen::Vector3d dphi(delta[3], delta[4], delta[5]);
  store_quaternion(block_rotation(x + 3) * so3_exp(dphi), x_plus_delta + 3);
  return true;
}

bool PoseManifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<6>().setIdentity();
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  for (int k = 0; k < 3; ++k) y_minus_x[k] = y[k] - x[k];
  const Eigen::Vector3d dphi = so3_log(block_rotation(x + 3).transpose() * block_rotation(y + 3));
  for (int k = 0; k < 3; ++k) y_minus_x[3 + k] = dphi[k];
  return true;
}

bool PoseManifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.leftCols<6>().setIdentity();
  return true;
}

bool RotationManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Vector3d dphi(delta[0], delta[1], delta[2]);
  store_quaternion(block_rotation(x) * so3_exp(dphi), x_plus_delta);
  return true;
}

bool RotationManifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<3>().setIdentity();
  return true;
}

bool RotationManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::Vector3d dphi = so3_log(block_rotation(x).transpose() * block_rotation(y));
  for (int k = 0; k < 3; ++k) y_minus_x[k] = dphi[k];
  return true;
}

bool RotationManifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.leftCols<3>().setIdentity();
  return true;
}

}  // namespace keel::slam
