// DVL samples from a servo tray taken back into the DVL's angle-0 frame, against the closed
// form of docs/mission-format.md's tray formula; the servo-angle line fit against a ramp.
#include "worker/pipeline/servo_tray.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <string>

namespace keel::pipeline {
namespace {

constexpr TimeNs kSecond = 1000000000;

Pose3 pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

double theta_at(double t_s) { return 0.9 * std::sin(0.4 * t_s); }

// A tray turning about its frame's y axis, the DVL on the pivot, pointing down the tray.
struct Tray {
  Pose3 T_body_servo =
      pose(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {0.6, 0.0, -0.1});
  Eigen::Vector3d axis_servo = Eigen::Vector3d::UnitY();
  Pose3 T_body_dvl0 =
      pose(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix(),
           {0.6, 0.0, -0.1});
  io::ServoSeries servo;  // 20 Hz, exact angles, 0..10 s
  Tray() {
    for (int k = 0; k <= 200; ++k) servo.push_back({k * kSecond / 20, theta_at(k / 20.0)});
  }
};

TEST(ServoTray, VelocitiesComeBackIntoTheAngleZeroFrame) {
  const Tray tray;
  const Eigen::Vector3d axis_body = tray.T_body_servo.linear() * tray.axis_servo;
  const Eigen::Matrix3d R_body_dvl0 = tray.T_body_dvl0.linear();
  std::vector<slam::DvlSample> samples;
  std::vector<Eigen::Vector3d> expected;
  for (int k = 0; k <= 100; ++k) {  // 10 Hz, at servo stamps: interpolation is exact there
    const double t = k / 10.0;
    const Eigen::Vector3d v_body(0.25 * std::cos(t), 0.1, -0.05 * std::sin(2 * t));
    const Eigen::Matrix3d R_body_dvl =
        Eigen::AngleAxisd(theta_at(t), axis_body).toRotationMatrix() * R_body_dvl0;
    samples.push_back({k * kSecond / 10, R_body_dvl.transpose() * v_body, true});
    expected.push_back(R_body_dvl0.transpose() * v_body);
  }
  const TrayDvlStats stats =
      rotate_tray_dvl(samples, tray.servo, tray.T_body_servo, tray.axis_servo, tray.T_body_dvl0, 0);
  EXPECT_EQ(stats.rotated, samples.size());
  EXPECT_EQ(stats.without_angle, 0u);
  double max_angle = 0;
  for (int k = 0; k <= 100; ++k) max_angle = std::max(max_angle, std::abs(theta_at(k / 10.0)));
  EXPECT_NEAR(stats.max_angle_rad, max_angle, 1e-12);
  for (size_t k = 0; k < samples.size(); ++k)
    EXPECT_LT((samples[k].velocity_mps - expected[k]).norm(), 1e-12) << k;
}

TEST(ServoTray, SamplesOutsideTheServoSeriesBecomeDropouts) {
  const Tray tray;
  std::vector<slam::DvlSample> samples = {{-kSecond, {0.1, 0, 0}, true},
                                          {5 * kSecond, {0.1, 0, 0}, true},
                                          {11 * kSecond, {0.1, 0, 0}, true},
                                          {6 * kSecond, {0.1, 0, 0}, false}};
  const TrayDvlStats stats = rotate_tray_dvl(samples, tray.servo, tray.T_body_servo,
                                             tray.axis_servo, tray.T_body_dvl0, kSecond / 2);
  EXPECT_EQ(stats.rotated, 1u);
  EXPECT_EQ(stats.without_angle, 2u);
  EXPECT_FALSE(samples[0].valid);
  EXPECT_TRUE(samples[1].valid);
  EXPECT_FALSE(samples[2].valid);
  EXPECT_FALSE(samples[3].valid);  // a dropout stays one, untouched
  EXPECT_EQ(samples[3].velocity_mps, Eigen::Vector3d(0.1, 0, 0));
}

TEST(ServoTray, ADvlOffTheTrayAxisIsRefused) {
  Tray tray;
  // 5 cm along the axis is still on it; 5 cm across it is not.
  tray.T_body_dvl0.translation() += 0.05 * (tray.T_body_servo.linear() * tray.axis_servo);
  std::vector<slam::DvlSample> samples = {{kSecond, {0.1, 0, 0}, true}};
  EXPECT_NO_THROW(rotate_tray_dvl(samples, tray.servo, tray.T_body_servo, tray.axis_servo,
                                  tray.T_body_dvl0, 0));
  tray.T_body_dvl0.translation() += Eigen::Vector3d(0, 0, 0.05);
  try {
    rotate_tray_dvl(samples, tray.servo, tray.T_body_servo, tray.axis_servo, tray.T_body_dvl0, 0);
    ADD_FAILURE() << "an off-axis DVL was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("0.05"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("off the tray's axis"), std::string::npos) << e.what();
  }
}

TEST(ServoTray, LineFitFollowsARampAndInterpolatesShortWindows) {
  io::ServoSeries ramp;
  for (int k = 0; k <= 40; ++k) ramp.push_back({k * kSecond / 20, 0.1 + 0.2 * k / 20.0});
  // t = 0.525 s, between samples: the fitted line and the interpolation both give the ramp.
  const TimeNs t = 525 * kSecond / 1000;
  EXPECT_NEAR(*servo_angle_at(ramp, t, kSecond / 2), 0.1 + 0.2 * 0.525, 1e-12);
  EXPECT_NEAR(*servo_angle_at(ramp, t, 0), 0.1 + 0.2 * 0.525, 1e-12);
  EXPECT_FALSE(servo_angle_at(ramp, -1, kSecond).has_value());
  EXPECT_FALSE(servo_angle_at(ramp, 2 * kSecond + 1, kSecond).has_value());
  EXPECT_FALSE(servo_angle_at({}, 0, kSecond).has_value());
}

}  // namespace
}  // namespace keel::pipeline
