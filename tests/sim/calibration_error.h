// keel-sim's `--set calibration_error.<sensor>=<pose>`: a mission whose declared extrinsic of
// a sensor (mission.yaml's T_body_sensor, the bags' /tf_static) is off by a known error while
// the data follow the true one (issue 31; docs/calibration.md). The pose is written as job
// overrides are: {"xyz_m": [3], "rpy_deg": [3]} (R = Rz(yaw) Ry(pitch) Rx(roll)) or
// {"translation": [3], "rotation_xyzw": [4]}.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/pose.h"

namespace keel::sim {

inline constexpr const char* kCalibrationErrorPrefix = "calibration_error.";

// By sensor: T_error, so that the declared extrinsic is T_body_sensor_true * T_error.
using CalibrationErrors = std::map<std::string, Pose3>;

// Moves the `calibration_error.<sensor>=<pose>` items out of `settings` (the others stay, in
// order) and parses them. Throws std::invalid_argument naming the setting.
CalibrationErrors take_calibration_errors(std::vector<std::string>* settings);

// The extrinsic a mission declares for `sensor`: `T_true`, times its error when it has one.
Pose3 declared_extrinsic(const CalibrationErrors& errors, const std::string& sensor,
                         const Pose3& T_true);

}  // namespace keel::sim
