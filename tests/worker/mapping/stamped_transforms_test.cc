// TF tree: interpolation against closed forms, long missions, errors outside the span.
#include <gtest/gtest.h>

#include <stdexcept>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/stamped_transforms.h"
#include "worker/mapping/transform_tree.h"

namespace keel::mapping {
namespace {

using testing::constant_rate_pose;
using testing::rotation_angle;
using testing::sample_trajectory;

TEST(StampedTransforms, ConstantRateRotationAndLinearTranslationAreExact) {
  const Eigen::Vector3d v(0.7, -1.3, 0.2);
  const double yaw_rate = 0.9;  // rad/s; 0.09 rad between samples
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  Trajectory samples;
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.1 * i;
    samples.push_back({std::llround(t * 1e9), constant_rate_pose(t, v, yaw_rate, axis)});
  }
  const StampedTransforms poses(samples);
  for (double t : {0.0, 0.0123, 3.14159, 5.55, 9.999999, 10.0}) {
    const Pose3 expected = constant_rate_pose(t, v, yaw_rate, axis);
    const Pose3 got = poses.at(std::llround(t * 1e9));
    EXPECT_LT((got.translation() - expected.translation()).norm(), 1e-9) << t;
    EXPECT_LT(rotation_angle(got, expected), 1e-9) << t;
  }
}

TEST(StampedTransforms, InterpolatePoseMidpointOfQuarterTurn) {
  const Pose3 a = make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  const Pose3 b =
      make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX())),
                Eigen::Vector3d(2, 4, 6));
  const Pose3 mid = interpolate_pose(a, b, 0.25);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.linear()).angle(), M_PI / 8, 1e-12);
  EXPECT_LT((mid.translation() - Eigen::Vector3d(0.5, 1, 1.5)).norm(), 1e-12);
}

TEST(StampedTransforms, MissionLongerThanAThousandSeconds) {
  const Eigen::Vector3d v(1.5, 0.25, -0.01);
  const double yaw_rate = 0.02;
  // 5000 s at 10 Hz, stamps far from zero like a real epoch.
  Trajectory samples;
  const double epoch = 1.7e9;
  for (int i = 0; i <= 50000; ++i) {
    const double t = 0.1 * i;
    samples.push_back(
        {std::llround(epoch * 1e9) + std::llround(t * 1e9), constant_rate_pose(t, v, yaw_rate)});
  }
  const StampedTransforms poses(samples);
  for (double t : {0.05, 999.97, 1000.03, 2500.5, 4321.25, 4999.95}) {
    const Pose3 got = poses.at(std::llround(epoch * 1e9) + std::llround(t * 1e9));
    const Pose3 expected = constant_rate_pose(t, v, yaw_rate);
    EXPECT_LT((got.translation() - expected.translation()).norm(), 1e-6) << t;
    EXPECT_LT(rotation_angle(got, expected), 1e-9) << t;
  }
}

TEST(StampedTransforms, OutsideTheSpanIsAnErrorNamingTimeAndSpan) {
  const StampedTransforms poses(sample_trajectory(10.0, 20.0, 0.5, {1, 0, 0}, 0.1));
  try {
    poses.at(seconds_to_ns(20.25));
    FAIL() << "no exception";
  } catch (const std::out_of_range& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("20.250000000"), std::string::npos) << message;
    EXPECT_NE(message.find("[10.000000000, 20.000000000]"), std::string::npos) << message;
  }
  EXPECT_THROW(poses.at(seconds_to_ns(9.999)), std::out_of_range);
  EXPECT_NO_THROW(poses.at(seconds_to_ns(10.0)));
  EXPECT_NO_THROW(poses.at(seconds_to_ns(20.0)));
  // Clamped lookups hold the end poses.
  EXPECT_LT(
      (poses.at_clamped(seconds_to_ns(25.0)).translation() - Eigen::Vector3d(20, 0, 0)).norm(),
      1e-12);
}

TEST(StampedTransforms, RejectsUnsortedDuplicateAndNonRigidSamples) {
  Trajectory samples = sample_trajectory(0.0, 1.0, 0.1, {1, 0, 0}, 0.0);
  Trajectory duplicate = samples;
  duplicate[4].t_ns = duplicate[3].t_ns;
  EXPECT_THROW(StampedTransforms(duplicate, "odom"), std::invalid_argument);
  Trajectory scaled = samples;
  scaled[2].T_world_body.linear() *= 2.0;
  EXPECT_THROW(StampedTransforms(scaled, "odom"), std::invalid_argument);
  Trajectory nan = samples;
  nan[5].T_world_body.translation().x() = std::nan("");
  EXPECT_THROW(StampedTransforms(nan, "odom"), std::invalid_argument);
  EXPECT_THROW(StampedTransforms(Trajectory{}, "odom"), std::invalid_argument);
  try {
    StampedTransforms(duplicate, "odom");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("odom sample 4"), std::string::npos) << e.what();
  }
}

TEST(TransformTree, ComposesStaticExtrinsicsByName) {
  TransformTree tree(sample_trajectory(0.0, 10.0, 0.1, {1, 2, 0}, 0.3));
  const Pose3 T_body_lidar =
      make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())),
                Eigen::Vector3d(0.2, 0.0, 0.5));
  tree.set_extrinsic("lidar_h", T_body_lidar);
  const TimeNs t = seconds_to_ns(4.321);
  const Pose3 expected = constant_rate_pose(4.321, {1, 2, 0}, 0.3) * T_body_lidar;
  const Pose3 got = tree.T_world_sensor("lidar_h", t);
  EXPECT_LT((got.translation() - expected.translation()).norm(), 1e-9);
  EXPECT_LT(rotation_angle(got, expected), 1e-9);
  try {
    tree.T_world_sensor("sonar", t);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'sonar'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("lidar_h"), std::string::npos);
  }
}

}  // namespace
}  // namespace keel::mapping
