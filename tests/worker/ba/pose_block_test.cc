// A pose block's translation covariance along its own axes: the closed form for a frame
// turned 90 degrees, and the tangent layout it assumes, checked on the manifold itself.
#include "worker/ba/pose_block.h"

#include <gtest/gtest.h>

namespace keel::ba {
namespace {

TEST(PoseBlock, TranslationSigmaTurnsIntoTheOwnAxes) {
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Random() * 1e-3;
  covariance.block<3, 3>(3, 3) = Eigen::Vector3d(0.04, 1e-4, 4e-4).asDiagonal();  // parent
  covariance.block<3, 3>(0, 3).setZero();
  covariance.block<3, 3>(3, 0).setZero();
  // The pose's x axis is the parent's y: sigma along own x is the parent's y sigma.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d sigma = translation_sigma_in_own_axes(covariance, R);
  EXPECT_NEAR(sigma.x(), 0.01, 1e-12);
  EXPECT_NEAR(sigma.y(), 0.2, 1e-12);
  EXPECT_NEAR(sigma.z(), 0.02, 1e-12);
}

TEST(PoseBlock, TangentIsRotationThenParentFrameTranslation) {
  // What translation_sigma_in_own_axes assumes of make_pose_manifold's tangent.
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1, 2, 3);
  const PoseBlock x = to_pose_block(T);
  const double delta[6] = {0, 0, 0, 0.5, 0, 0};
  PoseBlock moved;
  ASSERT_TRUE(make_pose_manifold()->Plus(x.data(), delta, moved.data()));
  const Pose3 after = from_pose_block(moved.data());
  EXPECT_TRUE(after.translation().isApprox(Eigen::Vector3d(1.5, 2, 3), 1e-12));
  EXPECT_TRUE(after.linear().isApprox(T.linear(), 1e-12));
}

}  // namespace
}  // namespace keel::ba
