// Ceres parameter blocks of the BA: a pose is 7 doubles [q_x q_y q_z q_w t_x t_y t_z]
// (Eigen's quaternion storage order, then the translation) on the manifold
// SO(3) x R^3 = ProductManifold<EigenQuaternionManifold, EuclideanManifold<3>>.
// The helpers are templates so the factors can be auto-differentiated.
#pragma once

#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <memory>

#include "core/pose.h"

namespace keel::ba {

constexpr int kPoseBlockSize = 7;
using PoseBlock = std::array<double, kPoseBlockSize>;

PoseBlock to_pose_block(const Pose3& T);
Pose3 from_pose_block(const double* block);
std::unique_ptr<ceres::Manifold> make_pose_manifold();

// Standard deviations of a pose block's translation along the axes of the pose's own frame,
// from its 6x6 covariance in the manifold's tangent space: [rotation (3), translation in the
// parent frame (3)], so the translation part turns by R_parent_pose^T.
Eigen::Vector3d translation_sigma_in_own_axes(const Eigen::Matrix<double, 6, 6>& tangent_covariance,
                                              const Eigen::Matrix3d& R_parent_pose);

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

template <typename T>
Eigen::Quaternion<T> block_rotation(const T* block) {
  return Eigen::Quaternion<T>(block[3], block[0], block[1], block[2]);
}
template <typename T>
Vec3<T> block_translation(const T* block) {
  return Vec3<T>(block[4], block[5], block[6]);
}

// T_a_b * p_b. The quaternion is normalised: Ceres keeps it unit, finite differences may not.
template <typename T>
Vec3<T> transform_point(const T* T_a_b, const Vec3<T>& p_b) {
  return block_rotation(T_a_b).normalized() * p_b + block_translation(T_a_b);
}
// T_a_b^-1 * p_a.
template <typename T>
Vec3<T> inverse_transform_point(const T* T_a_b, const Vec3<T>& p_a) {
  return block_rotation(T_a_b).normalized().conjugate() * (p_a - block_translation(T_a_b));
}

// Rotation of `angle` about the unit `axis`.
template <typename T>
Eigen::Quaternion<T> axis_angle_rotation(const Eigen::Vector3d& axis, const T& angle) {
  const T half = angle * T(0.5);
  const T s = sin(half);
  return Eigen::Quaternion<T>(cos(half), T(axis.x()) * s, T(axis.y()) * s, T(axis.z()) * s);
}

// Rotation vector (axis * angle) of a unit quaternion, for residuals. Uses atan2 so it is
// accurate and differentiable for small angles too (ceres::QuaternionToAngleAxis does the
// same; this one takes Eigen's storage order).
template <typename T>
Vec3<T> rotation_vector(const Eigen::Quaternion<T>& q_in) {
  Eigen::Quaternion<T> q = q_in;
  if (q.w() < T(0)) q.coeffs() = -q.coeffs();  // the shorter of the two equal rotations
  const Vec3<T> v = q.vec();
  const T sin_sq = v.squaredNorm();
  if (sin_sq > T(1e-20)) {
    const T sin_half = sqrt(sin_sq);
    const T angle = T(2.0) * atan2(sin_half, q.w());
    return v * (angle / sin_half);
  }
  return v * T(2.0);  // first order: angle / sin(angle/2) -> 2
}

}  // namespace keel::ba
