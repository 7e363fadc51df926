#include "worker/ba/pose_block.h"

#include <ceres/product_manifold.h>

namespace keel::ba {

PoseBlock to_pose_block(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  return {q.x(), q.y(), q.z(), q.w(), t.x(), t.y(), t.z()};
}

Pose3 from_pose_block(const double* block) {
  return make_pose(block_rotation(block), block_translation(block));
}

std::unique_ptr<ceres::Manifold> make_pose_manifold() {
  return std::make_unique<
      ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>>();
}

Eigen::Vector3d translation_sigma_in_own_axes(const Eigen::Matrix<double, 6, 6>& tangent_covariance,
                                              const Eigen::Matrix3d& R_parent_pose) {
  const Eigen::Matrix3d in_own =
      R_parent_pose.transpose() * tangent_covariance.block<3, 3>(3, 3) * R_parent_pose;
  return in_own.diagonal().cwiseMax(0.0).cwiseSqrt();
}

}  // namespace keel::ba
