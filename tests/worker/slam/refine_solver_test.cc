// The refine solver on a synthetic mission generated here (synthetic_mission.h): a figure-eight
// USV run whose odometry drifts and degenerates along the body x axis for 20 s.
#include "worker/slam/refine_solver.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <stdexcept>

#include "tests/worker/slam/synthetic_mission.h"
#include "worker/slam/so3.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::slam {
namespace {

using testing::make_synthetic_mission;
using testing::SyntheticMission;
using testing::SyntheticMissionOptions;

double ate_rmse(const Trajectory& truth, const Trajectory& estimate) {
  return absolute_trajectory_error(truth, estimate, Alignment::kSE3).translation_m.rmse;
}

Pose3 with_yaw(const Pose3& T, double yaw_rad) {
  Pose3 out = T;
  out.linear() = T.linear() * so3_exp(Eigen::Vector3d(0, 0, yaw_rad));
  return out;
}

TEST(RefineSolver, LowersAteBelowOdometryAndFurtherWithDvl) {
  SyntheticMissionOptions o;
  const SyntheticMission m = make_synthetic_mission(o);
  RefineOptions with_dvl;
  RefineOptions without_dvl;
  without_dvl.use_dvl = false;
  const RefineResult a = refine_trajectory(m.input, with_dvl);
  const RefineResult b = refine_trajectory(m.input, without_dvl);
  const double ate_odom = ate_rmse(m.ground_truth, m.odometry);
  const double ate_dvl = ate_rmse(m.ground_truth, a.trajectory());
  const double ate_imu = ate_rmse(m.ground_truth, b.trajectory());
  std::printf("ATE rmse: odometry %.3f m, refined without DVL %.3f m, with DVL %.3f m\n", ate_odom,
              ate_imu, ate_dvl);
  EXPECT_LT(ate_dvl, ate_odom);
  EXPECT_LT(ate_dvl, ate_imu);
  EXPECT_GT(a.summary.num_dvl_factors, 100);
  EXPECT_EQ(b.summary.num_dvl_factors, 0);
  EXPECT_TRUE(a.summary.covariance_ok);
}

// Seed 000's rule (imu_position_when_degenerate = false): degenerate keyframes lose their
// odometry factor and their biases are zeroed. By default the IMU factor keeps its position
// residual there, which makes the biases observable, so they are estimated instead.
TEST(RefineSolver, FlagsDegenerateKeyframesAndZeroesTheirBiasesUnderThePapersRule) {
  const SyntheticMission m = make_synthetic_mission(SyntheticMissionOptions{});
  for (bool imu_position : {false, true}) {
    RefineOptions options;
    options.imu_position_when_degenerate = imu_position;
    const RefineResult r = refine_trajectory(m.input, options);
    int flagged = 0;
    for (size_t k = 0; k < r.keyframes.size(); ++k) {
      const KeyframeEstimate& e = r.keyframes[k];
      EXPECT_EQ(e.degenerate, static_cast<bool>(m.degenerate_truth[k])) << k;
      if (k > 0) EXPECT_EQ(e.imu_position_with_dvl, imu_position && e.degenerate) << k;
      if (!e.degenerate) continue;
      ++flagged;
      EXPECT_FALSE(e.has_odometry_factor) << k;  // Sec. IV-B: rely on IMU and DVL
      EXPECT_TRUE(e.has_dvl_factor) << k;
      EXPECT_EQ(e.biases_zeroed, !imu_position) << k;
      if (imu_position) continue;
      EXPECT_EQ(e.bias_gyro_radps, Eigen::Vector3d::Zero());
      EXPECT_EQ(e.bias_dvl_mps, Eigen::Vector3d::Zero());
    }
    EXPECT_EQ(flagged, 20);
    EXPECT_EQ(r.summary.num_degenerate_keyframes, 20);
  }
}

TEST(RefineSolver, RecoversAnInjectedDvlScaleWithinThreeSigma) {
  SyntheticMissionOptions o;
  o.dvl_scale = 1.02;
  const SyntheticMission m = make_synthetic_mission(o);
  const RefineResult r = refine_trajectory(m.input, RefineOptions{});
  ASSERT_TRUE(r.summary.covariance_ok);
  std::printf("s_d = %.5f +- %.5f (true 1.02)\n", r.dvl_scale, r.dvl_scale_sigma);
  EXPECT_GT(r.dvl_scale_sigma, 0.0);
  EXPECT_LT(r.dvl_scale_sigma, 0.005);
  EXPECT_LT(std::abs(r.dvl_scale - 1.02), 3.0 * r.dvl_scale_sigma);
}

// With the default options (biases free in the degenerate keyframes, b^v_0 held to the DVL's
// accuracy by its prior), on several noise seeds: a lateral b^v free to absorb yaw x speed made
// the yaw wander (0.84 deg on seed 7 with a 0.05 m/s b^v prior).
TEST(RefineSolver, EstimatesTheDvlExtrinsicRotation) {
  for (uint64_t seed : {7, 1, 2, 3, 4}) {
    SyntheticMissionOptions o;
    o.seed = seed;
    const double yaw_error = 1.5 * M_PI / 180.0;
    o.T_body_dvl_true = with_yaw(Pose3::Identity(), yaw_error);
    o.T_body_dvl_true.translation() = Eigen::Vector3d(0.3, 0.0, -0.5);
    o.T_body_dvl_nominal = o.T_body_dvl_true;
    o.T_body_dvl_nominal.linear() = Eigen::Matrix3d::Identity();  // told: aligned
    const SyntheticMission m = make_synthetic_mission(o);
    const RefineResult r = refine_trajectory(m.input, RefineOptions{});
    ASSERT_TRUE(r.summary.covariance_ok);
    const Eigen::Vector3d err =
        so3_log(o.T_body_dvl_true.linear().transpose() * r.q_body_dvl.toRotationMatrix());
    const double sigma_yaw = std::sqrt(r.dvl_rotation_covariance(2, 2));
    std::printf(
        "seed %d: DVL yaw error after refinement %.4f deg (sigma %.4f deg), before %.2f deg\n",
        static_cast<int>(seed), err.z() * 180 / M_PI, sigma_yaw * 180 / M_PI,
        yaw_error * 180 / M_PI);
    EXPECT_LT(std::abs(err.z()), 3.0 * sigma_yaw) << seed;
    EXPECT_LT(std::abs(err.z()), 0.5 * yaw_error) << seed;
  }
}

// The outputs are compared byte for byte between runs, so the refinement must give the same
// bits on any number of threads. With its solve on several threads Ceres summed the residual
// blocks in the order the threads took them: the reported costs changed with the thread count.
TEST(RefineSolver, SameBitsOnAnyNumberOfThreads) {
  const SyntheticMission m = make_synthetic_mission(SyntheticMissionOptions{});
  RefineOptions options;
  options.covariances = CovarianceScope::kAll;
  options.num_threads = 1;
  const RefineResult one = refine_trajectory(m.input, options);
  ASSERT_TRUE(one.summary.covariance_ok);
  options.num_threads = 4;
  for (int run = 0; run < 2; ++run) {
    const RefineResult many = refine_trajectory(m.input, options);
    EXPECT_EQ(many.summary.initial_cost, one.summary.initial_cost);
    EXPECT_EQ(many.summary.final_cost, one.summary.final_cost);
    EXPECT_EQ(many.dvl_scale, one.dvl_scale);
    EXPECT_EQ(many.dvl_scale_sigma, one.dvl_scale_sigma);
    EXPECT_EQ(many.q_body_dvl.coeffs(), one.q_body_dvl.coeffs());
    EXPECT_EQ(many.dvl_rotation_covariance, one.dvl_rotation_covariance);
    ASSERT_EQ(many.keyframes.size(), one.keyframes.size());
    int differing = 0;
    for (size_t k = 0; k < one.keyframes.size(); ++k)
      differing +=
          many.keyframes[k].T_world_body.matrix() != one.keyframes[k].T_world_body.matrix() ||
          many.keyframes[k].pose_covariance != one.keyframes[k].pose_covariance;
    EXPECT_EQ(differing, 0);
  }
}

TEST(RefineSolver, DvlDropoutLeavesItsIntervalsWithoutDvlFactors) {
  SyntheticMissionOptions o;
  o.dvl_dropout_start_s = 20.5;
  o.dvl_dropout_duration_s = 4.0;  // samples 20.50 .. 24.45 s invalid
  const SyntheticMission m = make_synthetic_mission(o);
  const RefineResult r = refine_trajectory(m.input, RefineOptions{});
  // Intervals ending at keyframes 21 .. 25 overlap the unbridged gap (20.45 s .. 24.5 s).
  for (int k = 21; k <= 25; ++k) EXPECT_FALSE(r.keyframes[k].has_dvl_factor) << k;
  EXPECT_TRUE(r.keyframes[20].has_dvl_factor);
  EXPECT_TRUE(r.keyframes[26].has_dvl_factor);
  EXPECT_EQ(r.summary.num_dvl_intervals_skipped, 5);
  EXPECT_LT(ate_rmse(m.ground_truth, r.trajectory()), ate_rmse(m.ground_truth, m.odometry));
}

TEST(RefineSolver, HandlesABodyFrameDifferentFromTheImuFrame) {
  SyntheticMissionOptions o;
  o.T_body_imu = make_pose(Eigen::Quaterniond(so3_exp(Eigen::Vector3d(0, 0, M_PI / 2))),
                           Eigen::Vector3d(0.2, -0.1, 0.3));
  o.duration_s = 60.0;
  o.degenerate_start_s = -1.0;
  o.odom_yaw_drift_radps = 0.0;  // an unbiased odometry, so the gyro bias is unbiased too
  o.gyro_bias_radps = Eigen::Vector3d(2e-3, -1e-3, 3e-3);
  const SyntheticMission m = make_synthetic_mission(o);
  RefineOptions opt;
  opt.covariances = CovarianceScope::kAll;
  const RefineResult r = refine_trajectory(m.input, opt);
  EXPECT_LT(ate_rmse(m.ground_truth, r.trajectory()), 0.5 * ate_rmse(m.ground_truth, m.odometry));
  // The gyro bias is estimated and reported in the IMU frame (a frame mix-up would permute
  // and flip its x and y components, errors of ~3e-3 rad/s).
  ASSERT_TRUE(r.summary.covariance_ok);
  const KeyframeEstimate& last = r.keyframes.back();
  for (int k = 0; k < 3; ++k) {
    const double sigma = std::sqrt(last.bias_gyro_covariance(k, k));
    EXPECT_LT(std::abs(last.bias_gyro_radps[k] - o.gyro_bias_radps[k]), 3 * sigma)
        << k << ": " << last.bias_gyro_radps.transpose() << " sigma " << sigma;
    EXPECT_LT(sigma, 1e-3);
  }
  // Pose covariances come back in the body frame: positive definite, and the first keyframe
  // (held by the prior r_0) is the most certain.
  for (const KeyframeEstimate& e : r.keyframes) {
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(e.pose_covariance).eigenvalues()(0), 0.0);
  }
  EXPECT_LT(r.keyframes.front().pose_covariance.trace(),
            r.keyframes.back().pose_covariance.trace());
}

TEST(RefineSolver, LoopClosuresAloneCorrectDrift) {
  SyntheticMissionOptions o;
  o.duration_s = 200.0;  // more than one figure-eight period (180 s)
  o.degenerate_start_s = -1.0;
  o.loop_closures = true;
  const SyntheticMission m = make_synthetic_mission(o);
  ASSERT_GT(m.input.loop_closures.size(), 5u);
  RefineOptions pose_graph;
  pose_graph.use_imu = pose_graph.use_dvl = false;
  const RefineResult r = refine_trajectory(m.input, pose_graph);
  EXPECT_EQ(r.summary.num_imu_factors, 0);
  EXPECT_LT(ate_rmse(m.ground_truth, r.trajectory()), 0.7 * ate_rmse(m.ground_truth, m.odometry));
}

TEST(RefineSolver, RejectsBadInputWithClearErrors) {
  SyntheticMissionOptions o;
  o.duration_s = 5.0;
  o.degenerate_start_s = -1.0;
  const SyntheticMission m = make_synthetic_mission(o);
  auto expect_error = [](const RefineInput& in, const std::string& fragment) {
    try {
      refine_trajectory(in, RefineOptions{});
      ADD_FAILURE() << "expected std::invalid_argument mentioning " << fragment;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  RefineInput one = m.input;
  one.keyframes.resize(1);
  expect_error(one, "keyframes");
  RefineInput stray = m.input;
  stray.odometry[1].t_j_ns += 500'000'000;
  expect_error(stray, "odometry[1].t_j");
  RefineInput unsorted = m.input;
  std::swap(unsorted.imu[10], unsorted.imu[11]);
  expect_error(unsorted, "imu sample 11");
  RefineInput nan_pose = m.input;
  nan_pose.keyframes[2].T_world_body.translation().x() = std::nan("");
  expect_error(nan_pose, "keyframes[2]");
}

}  // namespace
}  // namespace keel::slam
