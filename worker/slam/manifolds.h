// Ceres parameter blocks for poses and rotations, perturbed like Forster et al. [27]:
//   pose block  = [p_x p_y p_z q_x q_y q_z q_w], tangent [delta p (world), delta phi (body)],
//                 p <- p + delta p, R <- R Exp(delta phi);
//   rotation    = [q_x q_y q_z q_w], tangent delta phi, R <- R Exp(delta phi).
// The cost functions of this folder write their Jacobians w.r.t. the tangent vector into the
// first TangentSize() columns of the ambient Jacobian and zeros into the rest, and PlusJacobian
// is the matching [I; 0] (the "lifted" convention of VINS-Mono and many Ceres SLAM back ends):
// the product Ceres forms, J_ambient * PlusJacobian, is then exactly the tangent Jacobian.
// So these manifolds must only be used with the cost functions of worker/slam.
#pragma once

#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keel::slam {

class PoseManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

class RotationManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Reading and writing the blocks.
inline Eigen::Vector3d block_position(const double* pose) {
  return Eigen::Vector3d(pose[0], pose[1], pose[2]);
}
inline Eigen::Matrix3d block_rotation(const double* quaternion_xyzw) {
  return Eigen::Quaterniond(quaternion_xyzw[3], quaternion_xyzw[0], quaternion_xyzw[1],
                            quaternion_xyzw[2])
      .normalized()
      .toRotationMatrix();
}
void set_pose_block(const Eigen::Isometry3d& T, double* pose);
Eigen::Isometry3d get_pose_block(const double* pose);
void set_rotation_block(const Eigen::Matrix3d& R, double* quaternion_xyzw);

// Writes a tangent Jacobian (row-major rows x tangent) into an ambient Jacobian (row-major
// rows x ambient), zero-padding the extra columns: the lifted convention above.
template <int kRows, int kTangent, int kAmbient, class Derived>
void set_lifted_jacobian(const Eigen::MatrixBase<Derived>& J_tangent, double* J_ambient) {
  Eigen::Map<Eigen::Matrix<double, kRows, kAmbient, Eigen::RowMajor>> J(J_ambient);
  J.template leftCols<kTangent>() = J_tangent;
  J.template rightCols<kAmbient - kTangent>().setZero();
}

}  // namespace keel::slam
