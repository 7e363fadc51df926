#include "worker/pipeline/pose_json.h"

#include <cmath>

#include "proto/contract_error.h"

namespace keel::pipeline {

using nlohmann::json;
using proto::ContractError;

// `size` numbers (any size when 0), finite, at `path`.
template <typename T>
std::vector<T> json_numbers(const json& value, const std::string& path, size_t size) {
  if (!value.is_array() || (size > 0 && value.size() != size))
    throw ContractError(path + ": expected " +
                        (size ? std::to_string(size) + " numbers" : "an array") + ", got " +
                        proto::json_type_name(value));
  std::vector<T> out;
  for (size_t i = 0; i < value.size(); ++i) {
    const T x = proto::FieldReader::convert<T>(value[i], path + "[" + std::to_string(i) + "]");
    if (!std::isfinite(double(x)))
      throw ContractError(path + "[" + std::to_string(i) + "]: expected a finite number");
    out.push_back(x);
  }
  return out;
}

template std::vector<double> json_numbers(const json&, const std::string&, size_t);
template std::vector<int> json_numbers(const json&, const std::string&, size_t);

json pose_to_json(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  return {{"translation", {T.translation().x(), T.translation().y(), T.translation().z()}},
          {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
}

Pose3 pose_from_json(const json& value, const std::string& path) {
  proto::FieldReader r(value, path);
  const auto t = json_numbers<double>(r.at("translation"), r.child("translation"), 3);
  const auto q = json_numbers<double>(r.at("rotation_xyzw"), r.child("rotation_xyzw"), 4);
  const Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
  if (std::abs(quat.norm() - 1.0) > 1e-3)
    throw ContractError(path + ".rotation_xyzw: expected a unit quaternion");
  return make_pose(quat, Eigen::Vector3d(t[0], t[1], t[2]));
}

}  // namespace keel::pipeline
