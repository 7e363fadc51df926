#include "worker/slam/degeneracy.h"

#include <gtest/gtest.h>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

TEST(Degeneracy, WellConstrainedInformationIsNotDegenerate) {
  Matrix6d info = Matrix6d::Identity() * 1e4;
  const DegeneracyReport r = analyze_degeneracy(info);
  EXPECT_FALSE(r.degenerate);
  EXPECT_LT((r.well_conditioned_information - info).norm(), 1e-9);
}

TEST(Degeneracy, FlagsASmallEigenvalueAlongARotatedAxisAndRemovesOnlyIt) {
  // A corridor along u: translation information tiny along u, large across it.
  const Eigen::Vector3d u = Eigen::Vector3d(1, 1, 0).normalized();
  const Eigen::Matrix3d R = so3_exp(Eigen::Vector3d(0.2, -0.1, 0.4));
  Matrix6d info = Matrix6d::Identity() * 1e4;
  info.block<3, 3>(0, 0) =
      1e4 * (Eigen::Matrix3d::Identity() - u * u.transpose()) + 1e-2 * u * u.transpose();
  info.block<3, 3>(0, 0) = R * info.block<3, 3>(0, 0) * R.transpose();
  const DegeneracyReport r = analyze_degeneracy(info);
  EXPECT_TRUE(r.degenerate);
  EXPECT_NEAR(r.eigenvalues_translation(0), 1e-2, 1e-6);
  EXPECT_NEAR(r.eigenvalues_rotation(0), 1e4, 1e-6);
  const Eigen::Vector3d axis = R * u;
  // The kept information sees nothing along the degenerate axis and all of the rest.
  EXPECT_LT((r.well_conditioned_information.block<3, 3>(0, 0) * axis).norm(), 1e-6);
  const Eigen::Vector3d across = R * Eigen::Vector3d(0, 0, 1);
  EXPECT_NEAR(across.dot(r.well_conditioned_information.block<3, 3>(0, 0) * across), 1e4, 1e-6);
}

TEST(Degeneracy, RelativeTestCatchesAWeakAxisAboveTheAbsoluteThreshold) {
  Matrix6d info = Matrix6d::Identity() * 1e6;
  info(0, 0) = 5e3;  // sigma 1.4 cm: fine in absolute terms, but 200x weaker than y and z
  EXPECT_TRUE(analyze_degeneracy(info).degenerate);
  DegeneracyOptions absolute_only;
  absolute_only.min_eigenvalue_ratio = 0.0;
  EXPECT_FALSE(analyze_degeneracy(info, absolute_only).degenerate);
}

TEST(Degeneracy, RotationThresholdIsSeparate) {
  Matrix6d info = Matrix6d::Identity() * 1e4;
  info.diagonal().tail<3>().setConstant(300.0);
  info(5, 5) = 50.0;  // yaw sigma 0.14 rad > 0.1 rad
  EXPECT_TRUE(analyze_degeneracy(info).degenerate);
  info(5, 5) = 200.0;  // 0.07 rad, within the ratio of the other rotation axes
  EXPECT_FALSE(analyze_degeneracy(info).degenerate);
}

}  // namespace
}  // namespace keel::slam
