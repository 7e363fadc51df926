#include "worker/mapping/transform_tree.h"

#include <stdexcept>

namespace keel::mapping {

TransformTree::TransformTree(const Trajectory& T_world_body, std::string name)
    : poses_(T_world_body, std::move(name)) {}

void TransformTree::set_extrinsic(const std::string& sensor, const Pose3& T_body_sensor) {
  const Eigen::Matrix3d R = T_body_sensor.linear();
  const bool finite = R.allFinite() && T_body_sensor.translation().allFinite();
  if (!finite || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      R.determinant() < 0.0) {
    throw std::invalid_argument("T_body_sensor of sensor '" + sensor +
                                "': expected a finite rigid transform");
  }
  T_body_sensor_[sensor] = T_body_sensor;
}

const Pose3& TransformTree::T_body_sensor(const std::string& sensor) const {
  const auto found = T_body_sensor_.find(sensor);
  if (found == T_body_sensor_.end()) {
    std::string known;
    for (const auto& [name, T] : T_body_sensor_) known += (known.empty() ? "" : ", ") + name;
    throw std::invalid_argument("no extrinsic T_body_sensor for sensor '" + sensor +
                                "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  return found->second;
}

std::vector<std::string> TransformTree::sensors() const {
  std::vector<std::string> names;
  for (const auto& [name, T] : T_body_sensor_) names.push_back(name);
  return names;
}

Pose3 TransformTree::T_world_sensor(const std::string& sensor, TimeNs t_ns) const {
  return T_world_body(t_ns) * T_body_sensor(sensor);
}

}  // namespace keel::mapping
