// Algorithm 2: a known drift injected into odometry is recovered from sparse MAP poses.
#include <gtest/gtest.h>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/odometry_correction.h"
#include "worker/mapping/stamped_transforms.h"

namespace keel::mapping {
namespace {

using testing::rotation_angle;

// Ground truth: a curvy path, not constant-rate.
Pose3 truth(double t) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3 * std::sin(0.2 * t), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.05 * std::cos(0.5 * t), Eigen::Vector3d::UnitX()));
  return make_pose(q, Eigen::Vector3d(2.0 * t, 5.0 * std::sin(0.1 * t), 0.1 * t));
}

// The injected correction T_WW'(t): yaw drifting at a constant rate about z and translation
// drifting linearly, so slerp/lerp between MAP stamps reproduces it exactly.
Pose3 drift(double t) {
  return make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.01 * t, Eigen::Vector3d::UnitZ())),
                   Eigen::Vector3d(0.03 * t, -0.02 * t, 0.005 * t));
}

Trajectory odometry(double t0, double t1, double dt, Pose3 (*correction)(double)) {
  Trajectory out;
  for (long i = 0; i <= std::lround((t1 - t0) / dt); ++i) {
    const double t = t0 + i * dt;
    // T_W'B = T_WW'^-1 T_WB.
    out.push_back({std::llround(t * 1e9), correction(t).inverse() * truth(t)});
  }
  return out;
}

Trajectory map_poses(double t0, double t1, double dt) {
  Trajectory out;
  for (long i = 0; i <= std::lround((t1 - t0) / dt); ++i) {
    const double t = t0 + i * dt;
    out.push_back({std::llround(t * 1e9), truth(t)});
  }
  return out;
}

void expect_matches_truth(const Trajectory& refined, double tolerance_m, double tolerance_rad) {
  for (const StampedPose& pose : refined) {
    const Pose3 expected = truth(ns_to_seconds(pose.t_ns));
    ASSERT_LT((pose.T_world_body.translation() - expected.translation()).norm(), tolerance_m)
        << format_seconds(pose.t_ns);
    ASSERT_LT(rotation_angle(pose.T_world_body, expected), tolerance_rad)
        << format_seconds(pose.t_ns);
  }
}

TEST(OdometryCorrection, RecoversInjectedCorrection) {
  // Lidar odometry at 10 Hz over 100 s; MAP keyframes at ~1 Hz, off the odometry stamps by 3 ms.
  const Trajectory odom = odometry(0.0, 100.0, 0.1, drift);
  const Trajectory keyframes = map_poses(0.003, 99.003, 1.0);
  const OdometryCorrection result = correct_odometry(keyframes, odom);
  ASSERT_EQ(result.refined.size(), odom.size());
  EXPECT_EQ(result.corrections.size(), keyframes.size());
  // Lines 3-17: the corrections are the injected drift at the MAP stamps. The odometry is
  // interpolated there, so the curvy truth costs a little.
  for (const StampedPose& c : result.corrections) {
    const Pose3 expected = drift(ns_to_seconds(c.t_ns));
    EXPECT_LT((c.T_world_body.translation() - expected.translation()).norm(), 2e-3);
    EXPECT_LT(rotation_angle(c.T_world_body, expected), 1e-4);
  }
  // Inside the keyframe span the refined poses are the truth; odometry samples outside it
  // hold the nearest correction: T_WB = T_WW'(first or last MAP stamp) * T_W'B^odom.
  Trajectory inside;
  size_t outside = 0;
  for (size_t i = 0; i < result.refined.size(); ++i) {
    const StampedPose& p = result.refined[i];
    if (p.t_ns >= keyframes.front().t_ns && p.t_ns <= keyframes.back().t_ns) {
      inside.push_back(p);
      continue;
    }
    ++outside;
    const Pose3& held =
        (p.t_ns < keyframes.front().t_ns ? result.corrections.front() : result.corrections.back())
            .T_world_body;
    const Pose3 expected = held * odom[i].T_world_body;
    EXPECT_LT((p.T_world_body.translation() - expected.translation()).norm(), 1e-9);
    EXPECT_LT(rotation_angle(p.T_world_body, expected), 1e-9);
  }
  expect_matches_truth(inside, 3e-3, 1e-4);
  EXPECT_EQ(outside, 11u);  // 0.0 before the first MAP pose, 99.1 .. 100.0 after the last
}

TEST(OdometryCorrection, DropsOdometryOutsideWhenAsked) {
  const Trajectory odom = odometry(0.0, 20.0, 0.1, drift);
  const Trajectory keyframes = map_poses(1.0, 19.0, 1.0);
  const OdometryCorrection result = correct_odometry(keyframes, odom, {false});
  EXPECT_EQ(result.odometry_poses_dropped, 20u);  // 0.0..0.9 and 19.1..20.0
  EXPECT_EQ(result.refined.front().t_ns, keyframes.front().t_ns);
  expect_matches_truth(result.refined, 1e-3, 1e-5);
}

Pose3 imu_drift(double t) {
  return make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(-0.02 * t, Eigen::Vector3d::UnitZ())),
                   Eigen::Vector3d(-0.1 * t, 0.05 * t, 0.0));
}

TEST(OdometryCorrection, ChainsLidarThenImuOdometry) {
  // As Sec. VI-C: lidar odometry corrected by MAP poses, then 200 Hz IMU odometry corrected by
  // the corrected lidar odometry; every IMU stamp gets a globally consistent pose.
  const Trajectory keyframes = map_poses(0.0, 60.0, 2.0);
  const Trajectory lidar = odometry(0.0, 60.0, 0.1, drift);
  const Trajectory imu = odometry(0.0, 60.0, 0.005, imu_drift);
  const Trajectory lidar_refined = correct_odometry(keyframes, lidar).refined;
  const OdometryCorrection imu_result = correct_odometry(lidar_refined, imu);
  EXPECT_EQ(imu_result.refined.size(), imu.size());
  // The second stage interpolates the first stage's output at 10 Hz: cm-level.
  expect_matches_truth(imu_result.refined, 5e-3, 2e-4);
}

TEST(OdometryCorrection, NoMapPoseInsideTheOdometryIsAnError) {
  const Trajectory odom = odometry(0.0, 10.0, 0.1, drift);
  const Trajectory keyframes = map_poses(20.0, 30.0, 1.0);
  EXPECT_THROW(correct_odometry(keyframes, odom), std::invalid_argument);
}

}  // namespace
}  // namespace keel::mapping
