#include "proto/calibration.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <cmath>
#include <string>

#include "proto/contract_error.h"
#include "proto/options.h"

namespace keel::proto {
namespace {

using nlohmann::json;

constexpr double kRadPerDeg = M_PI / 180.0;

Eigen::Quaterniond quaternion(const Extrinsic& e) {
  return {e.rotation_xyzw[3], e.rotation_xyzw[0], e.rotation_xyzw[1], e.rotation_xyzw[2]};
}

// The message of the ContractError `f` throws ("" when it throws none).
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const ContractError& e) {
    return e.what();
  }
  return "";
}

TEST(Calibration, RpyIsFixedAxisXyzAsEigenAngleAxisComposes) {
  for (const auto& rpy : {std::array<double, 3>{10.0, -25.0, 140.0},
                          {0.0, 90.0, 0.0},
                          {-170.0, 45.0, -60.0},
                          {3.0, 0.0, 0.0}}) {
    const Eigen::Matrix3d expected =
        (Eigen::AngleAxisd(rpy[2] * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(rpy[1] * kRadPerDeg, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(rpy[0] * kRadPerDeg, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Extrinsic e = pose_from_json(json{{"xyz_m", {1.0, -2.0, 0.5}}, {"rpy_deg", rpy}}, "p");
    EXPECT_TRUE(quaternion(e).toRotationMatrix().isApprox(expected, 1e-12));
    EXPECT_NEAR(quaternion(e).norm(), 1.0, 1e-12);
    EXPECT_EQ(e.translation, (std::array<double, 3>{1.0, -2.0, 0.5}));
    if (std::abs(rpy[1]) < 89.0) {  // away from gimbal lock the angles come back
      const auto back = rpy_deg_from_quaternion(e.rotation_xyzw);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(back[i], rpy[i], 1e-9);
    }
  }
}

TEST(Calibration, ParsesBothPoseFormsAndBothKeys) {
  const json calibration = {
      {"lidar_v", {{"T_body_sensor", {{"xyz_m", {0.1, 0, 0.4}}, {"rpy_deg", {0, 90, 0}}}}}},
      {"sonar",
       {{"T_lidar_h_sonar", {{"translation", {0.2, 0, -0.6}}, {"rotation_xyzw", {0, 0, 0, 1}}}}}},
      {"dvl", {{"T_body_dvl", {{"xyz_m", {0, 0, 0}}, {"rpy_deg", {0, 0, 0}}}}}}};
  const auto overrides = parse_calibration(calibration);
  ASSERT_EQ(overrides.size(), 3u);
  EXPECT_EQ(overrides[0].sensor, "dvl");
  EXPECT_EQ(overrides[0].reference, "");  // T_body_<sensor> is the body frame too
  EXPECT_EQ(overrides[1].sensor, "lidar_v");
  EXPECT_EQ(overrides[1].reference, "");
  EXPECT_EQ(overrides[1].path(), "calibration.lidar_v.T_body_sensor");
  EXPECT_EQ(overrides[2].reference, "lidar_h");  // a reference with an underscore
  EXPECT_EQ(overrides[2].key, "T_lidar_h_sonar");
  EXPECT_DOUBLE_EQ(overrides[2].T_reference_sensor.rotation_xyzw[3], 1.0);
  EXPECT_DOUBLE_EQ(overrides[2].T_reference_sensor.translation[2], -0.6);
  EXPECT_TRUE(parse_calibration(nullptr).empty());
}

TEST(Calibration, ErrorsNameTheOptionPath) {
  const json pose = {{"xyz_m", {0, 0, 0}}, {"rpy_deg", {0, 0, 0}}};
  EXPECT_EQ(error_of([] { parse_calibration(json::array()); }),
            "calibration: expected an object {\"<sensor>\": {\"T_body_sensor\": pose}}, got array");
  EXPECT_EQ(
      error_of([&] {
        parse_calibration({{"sonar", json::object()}});
      }),
      "calibration.sonar: expected one key, T_body_sensor or T_<reference>_sonar, got 0 keys");
  EXPECT_EQ(
      error_of([&] {
        parse_calibration({{"sonar", {{"T_body_sensor", pose}, {"T_lidar_h_sonar", pose}}}});
      }),
      "calibration.sonar: expected one key, T_body_sensor or T_<reference>_sonar, got 2 keys");
  EXPECT_EQ(error_of([&] {
              parse_calibration({{"sonar", {{"T_lidar_h_dvl", pose}}}});
            }),
            "calibration.sonar.T_lidar_h_dvl: expected T_body_sensor or T_<reference>_sonar");
  EXPECT_EQ(error_of([&] {
              parse_calibration({{"sonar", {{"T_sonar_sonar", pose}}}});
            }),
            "calibration.sonar.T_sonar_sonar: a sensor cannot be its own reference");
  EXPECT_EQ(error_of([&] {
              parse_calibration(
                  {{"sonar", {{"T_body_sensor", {{"xyz_m", {0, 0}}, {"rpy_deg", {0, 0, 0}}}}}}});
            }),
            "calibration.sonar.T_body_sensor.xyz_m: expected 3 numbers, got 2 items");
  EXPECT_EQ(error_of([&] {
              parse_calibration({{"sonar", {{"T_body_sensor", {{"xyz_m", {0, 0, 0}}}}}}});
            }),
            "calibration.sonar.T_body_sensor.rpy_deg: missing required field");
  EXPECT_EQ(
      error_of([&] {
        parse_calibration(
            {{"sonar", {{"T_body_sensor", {{"xyz_m", {0, 0, 0}}, {"rpy_deg", {0, "x", 0}}}}}}});
      }),
      "calibration.sonar.T_body_sensor.rpy_deg[1]: expected a finite number, got \"x\"");
  EXPECT_NE(
      error_of([&] {
        parse_calibration({{"sonar", {{"T_body_sensor", {{"xyz_m", {0, 0, 0}}, {"yaw", 1}}}}}});
      }).find("calibration.sonar.T_body_sensor"),
      std::string::npos);
  EXPECT_EQ(error_of([&] {
              parse_calibration({{"sonar", {{"T_body_sensor", 3}}}});
            }).rfind("calibration.sonar.T_body_sensor: expected a pose", 0),
            0u);
  EXPECT_EQ(
      error_of([&] {
        parse_calibration(
            {{"sonar",
              {{"T_body_sensor", {{"translation", {0, 0, 0}}, {"rotation_xyzw", {0, 0, 0, 0}}}}}}});
      }).rfind("calibration.sonar.T_body_sensor.rotation_xyzw", 0),
      0u);
}

TEST(CalibrationOptions, SetAssignmentsNestAndReplaceTheSensorsKey) {
  json options;
  apply_option_assignment(options, "map.voxel_m=0.1");
  apply_option_assignment(
      options, R"(calibration.sonar.T_body_sensor={"xyz_m":[1,2,3],"rpy_deg":[0,0,90]})");
  apply_option_assignment(
      options, R"(calibration.lidar_v.T_lidar_h_lidar_v={"xyz_m":[0,0,0],"rpy_deg":[0,90,0]})");
  apply_option_assignment(
      options, R"(calibration.sonar.T_lidar_h_sonar={"xyz_m":[0,0,1],"rpy_deg":[0,0,0]})");
  EXPECT_EQ(options["map"]["voxel_m"], 0.1);
  EXPECT_EQ(options["calibration"]["sonar"].size(), 1u);  // one key per sensor: the last one
  EXPECT_EQ(options["calibration"]["sonar"]["T_lidar_h_sonar"]["xyz_m"], json({0, 0, 1}));
  EXPECT_EQ(options["calibration"]["lidar_v"]["T_lidar_h_lidar_v"]["rpy_deg"], json({0, 90, 0}));
  EXPECT_NO_THROW(validate_options(options, "options"));

  EXPECT_EQ(
      error_of([&] { apply_option_assignment(options, "calibration.sonar.T_body_sensor=oops"); }),
      "calibration.sonar.T_body_sensor: expected a JSON pose {\"xyz_m\": [x, y, z], "
      "\"rpy_deg\": [roll, pitch, yaw]}, got 'oops'");
  EXPECT_EQ(error_of([&] {
              apply_option_assignment(options,
                                      R"(calibration.sonar.T_body_sensor={"xyz_m":[1,2]})");
            }),
            "calibration.sonar.T_body_sensor.xyz_m: expected 3 numbers, got 2 items");
  EXPECT_NE(error_of([&] { apply_option_assignment(options, "calibration.=1"); }), "");
  // A failed assignment leaves the options as they were.
  EXPECT_EQ(options["calibration"]["sonar"]["T_lidar_h_sonar"]["xyz_m"], json({0, 0, 1}));
}

TEST(CalibrationOptions, ValidateOptionsNamesThePath) {
  EXPECT_EQ(error_of([] {
              validate_options({{"calibration", {{"sonar", {{"T_body_sensor", {{"xyz_m", 1}}}}}}}},
                               "options");
            }).rfind("options.calibration.sonar.T_body_sensor.", 0),
            0u);
  EXPECT_EQ(error_of([] {
              validate_options({{"calibration", 1}}, "options");
            }),
            "options.calibration: expected an object {\"<sensor>\": {\"T_body_sensor\": pose}}, "
            "got integer");
  EXPECT_NO_THROW(validate_options({{"calibration", nullptr}}, "options"));
}

}  // namespace
}  // namespace keel::proto
