#include "tests/sim/calibration_error.h"

#include <nlohmann/json.hpp>

#include <stdexcept>

#include "proto/calibration.h"

namespace keel::sim {

CalibrationErrors take_calibration_errors(std::vector<std::string>* settings) {
  CalibrationErrors errors;
  std::vector<std::string> rest;
  const std::string prefix = kCalibrationErrorPrefix;
  for (const std::string& item : *settings) {
    if (item.compare(0, prefix.size(), prefix) != 0) {
      rest.push_back(item);
      continue;
    }
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq);
    const std::string sensor = key.substr(prefix.size());
    if (eq == std::string::npos || sensor.empty())
      throw std::invalid_argument("--set " + item +
                                  ": expected calibration_error.<sensor>={\"xyz_m\": [x, y, z], "
                                  "\"rpy_deg\": [roll, pitch, yaw]}");
    const nlohmann::json value =
        nlohmann::json::parse(item.substr(eq + 1), nullptr, /*allow_exceptions=*/false);
    if (value.is_discarded())
      throw std::invalid_argument("--set " + key +
                                  ": expected a JSON pose {\"xyz_m\": [x, y, z], "
                                  "\"rpy_deg\": [roll, pitch, yaw]}, got '" +
                                  item.substr(eq + 1) + "'");
    proto::Extrinsic e;
    try {
      e = proto::pose_from_json(value, "--set " + key);
    } catch (const std::exception& error) {
      throw std::invalid_argument(error.what());
    }
    const auto& q = e.rotation_xyzw;
    const auto& t = e.translation;
    errors[sensor] =
        make_pose(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
  }
  *settings = std::move(rest);
  return errors;
}

Pose3 declared_extrinsic(const CalibrationErrors& errors, const std::string& sensor,
                         const Pose3& T_true) {
  const auto it = errors.find(sensor);
  return it == errors.end() ? T_true : T_true * it->second;
}

}  // namespace keel::sim
