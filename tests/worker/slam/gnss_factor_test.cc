// GNSS position factor: placement between keyframes, the residual against the interpolation
// closed form, Jacobians against central differences on the pose manifold, and the gate
// (an outlier of 10 sigma out, a fix at 1 sigma in).
#include "worker/slam/gnss_factor.h"

#include <gtest/gtest.h>

#include "core/pose.h"
#include "worker/slam/manifolds.h"

namespace keel::slam {
namespace {

Pose3 pose_of(double yaw, const Eigen::Vector3d& p) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

TEST(GnssFactor, PlacesFixesBetweenKeyframesAndNotOutside) {
  const std::vector<TimeNs> t = {1000000000, 2000000000, 3000000000};
  std::vector<GnssFix> fixes(5);
  fixes[0].t_ns = 500000000;   // before
  fixes[1].t_ns = 1250000000;  // k 0, alpha 0.25
  fixes[2].t_ns = 2000000000;  // k 1, alpha 0
  fixes[3].t_ns = 3000000000;  // on the last keyframe: k 1, alpha 1
  fixes[4].t_ns = 3000000001;  // after
  const auto at = place_gnss_fixes(fixes, t, {});
  EXPECT_EQ(at[0].k, -1);
  EXPECT_EQ(at[1].k, 0);
  EXPECT_DOUBLE_EQ(at[1].alpha, 0.25);
  EXPECT_EQ(at[2].k, 1);
  EXPECT_DOUBLE_EQ(at[2].alpha, 0.0);
  EXPECT_EQ(at[3].k, 1);
  EXPECT_DOUBLE_EQ(at[3].alpha, 1.0);
  EXPECT_EQ(at[4].k, -1);
}

TEST(GnssFactor, ResidualIsTheInterpolatedAntennaAndJacobiansMatchDifferences) {
  const Pose3 Ti = pose_of(0.3, {1, 2, 0.5}), Tj = pose_of(0.9, {3, 1, 0.7});
  const Eigen::Vector3d lever(-0.5, 0.2, 2.0);
  GnssFix fix;
  fix.antenna_world_m = {2.0, 2.5, 3.0};
  fix.covariance_m2 = Eigen::Vector3d(0.25, 0.36, 1.0).asDiagonal();
  const double alpha = 0.3;
  GnssPositionFactor factor(fix, alpha, lever);
  double bi[7], bj[7];
  set_pose_block(Ti, bi);
  set_pose_block(Tj, bj);
  const Eigen::Vector3d expected_antenna = (1 - alpha) * (Ti * lever) + alpha * (Tj * lever);
  const Eigen::Vector3d expected = Eigen::Vector3d(1 / 0.5, 1 / 0.6, 1 / 1.0).asDiagonal() *
                                   (expected_antenna - fix.antenna_world_m);
  EXPECT_LT((factor.whitened(bi, bj) - expected).norm(), 1e-12);

  const double* params[2] = {bi, bj};
  double residual[3], J[2][21];
  double* jacobians[2] = {J[0], J[1]};
  ASSERT_TRUE(factor.Evaluate(params, residual, jacobians));
  PoseManifold manifold;
  for (int b = 0; b < 2; ++b) {
    const double* x = b == 0 ? bi : bj;
    for (int d = 0; d < 6; ++d) {
      double delta[6] = {0, 0, 0, 0, 0, 0}, plus[7], minus[7];
      const double h = 1e-6;
      delta[d] = h;
      manifold.Plus(x, delta, plus);
      delta[d] = -h;
      manifold.Plus(x, delta, minus);
      const Eigen::Vector3d numeric =
          (b == 0 ? factor.whitened(plus, bj) - factor.whitened(minus, bj)
                  : factor.whitened(bi, plus) - factor.whitened(bi, minus)) /
          (2 * h);
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(J[b][r * 7 + d], numeric[r], 1e-6) << b << d;
    }
    for (int r = 0; r < 3; ++r) EXPECT_EQ(J[b][r * 7 + 6], 0.0);  // lifted convention
  }
}

TEST(GnssFactor, GateLeavesOutTheOutlierAndCountsIt) {
  double blocks[2][7];
  set_pose_block(pose_of(0.0, {0, 0, 0}), blocks[0]);
  set_pose_block(pose_of(0.0, {1, 0, 0}), blocks[1]);
  std::vector<GnssFix> fixes(3);
  for (auto& f : fixes) f.covariance_m2 = 0.25 * Eigen::Matrix3d::Identity();
  fixes[0].t_ns = 0, fixes[0].antenna_world_m = {0.5, 0.0, 0.0};     // 1 sigma off
  fixes[1].t_ns = 500, fixes[1].antenna_world_m = {0.5, 5.0, 0.0};   // 10 sigma off
  fixes[2].t_ns = 2000, fixes[2].antenna_world_m = {1.0, 0.0, 0.0};  // after the keyframes
  ceres::Problem problem;
  std::vector<GnssFixUse> use;
  const auto counts = add_gnss_factors(
      problem, fixes, place_gnss_fixes(fixes, {0, 1000}, {}), [&](size_t k) { return blocks[k]; },
      Eigen::Vector3d::Zero(), {}, /*gate=*/true, &use);
  EXPECT_EQ(counts.used, 1);
  EXPECT_EQ(counts.rejected, 1);
  EXPECT_EQ(counts.outside, 1);
  EXPECT_EQ(use[0], GnssFixUse::kUsed);
  EXPECT_EQ(use[1], GnssFixUse::kRejected);
  EXPECT_EQ(use[2], GnssFixUse::kOutside);
  EXPECT_EQ(problem.NumResidualBlocks(), 1);
}

}  // namespace
}  // namespace keel::slam
