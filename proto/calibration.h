// A job's extrinsic overrides: the `calibration` object of its options (docs/calibration.md,
// section 1), {"<sensor>": {"T_body_sensor" | "T_<reference>_<sensor>": pose}}, and the two
// written forms of a pose.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

#include "proto/mission_manifest.h"

namespace keel::proto {

// The key of a job's options that holds the overrides (beside the stages' keys).
inline constexpr const char* kCalibrationOption = "calibration";

// One sensor's override: T_reference_sensor, the reference being the body frame or a sensor.
struct ExtrinsicOverride {
  std::string sensor;
  std::string reference;  // empty: the body frame (key T_body_sensor or T_body_<sensor>)
  std::string key;        // as written: "T_body_sensor", "T_lidar_h_sonar"
  Extrinsic T_reference_sensor;

  std::string path() const { return std::string(kCalibrationOption) + "." + sensor + "." + key; }
};

// R = Rz(yaw) * Ry(pitch) * Rx(roll) (ROS/URDF fixed axes X-Y-Z) as a unit quaternion x, y, z, w.
std::array<double, 4> quaternion_from_rpy_deg(const std::array<double, 3>& rpy_deg);
// The inverse, roll and yaw in (-180, 180], pitch in [-90, 90].
std::array<double, 3> rpy_deg_from_quaternion(const std::array<double, 4>& xyzw);

// {"xyz_m": [x, y, z], "rpy_deg": [roll, pitch, yaw]} or mission.yaml's {"translation": [3],
// "rotation_xyzw": [4]}. Fails naming `path` and the field.
Extrinsic pose_from_json(const nlohmann::json& value, const std::string& path);
// {"xyz_m": [..], "rpy_deg": [..]}, the form people type.
nlohmann::json pose_to_rpy_json(const Extrinsic& pose);

// Parses the `calibration` object (null: no overrides), in sensor-name order. Checks the form
// only (which sensors exist is the mission's business): one key per sensor, the key
// `T_body_sensor` or `T_<reference>_<sensor>`, a pose. Errors name the option path under `path`.
std::vector<ExtrinsicOverride> parse_calibration(const nlohmann::json& calibration,
                                                 const std::string& path = kCalibrationOption);

}  // namespace keel::proto
