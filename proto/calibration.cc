#include "proto/calibration.h"

#include <algorithm>
#include <cmath>

#include "proto/contract_error.h"

namespace keel::proto {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadPerDeg = kPi / 180.0;

template <size_t N>
std::array<double, N> finite_numbers(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array() || value.size() != N)
    throw ContractError(
        path + ": expected " + std::to_string(N) + " numbers, got " +
        (value.is_array() ? std::to_string(value.size()) + " items" : json_type_name(value)));
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) {
    if (!value[i].is_number() || !std::isfinite(value[i].get<double>()))
      throw ContractError(path + "[" + std::to_string(i) + "]: expected a finite number, got " +
                          value[i].dump());
    out[i] = value[i].get<double>();
  }
  return out;
}

}  // namespace

std::array<double, 4> quaternion_from_rpy_deg(const std::array<double, 3>& rpy_deg) {
  // q = qz(yaw) * qy(pitch) * qx(roll), multiplied out.
  const double hr = 0.5 * rpy_deg[0] * kRadPerDeg, hp = 0.5 * rpy_deg[1] * kRadPerDeg,
               hy = 0.5 * rpy_deg[2] * kRadPerDeg;
  const double cr = std::cos(hr), sr = std::sin(hr), cp = std::cos(hp), sp = std::sin(hp),
               cy = std::cos(hy), sy = std::sin(hy);
  return {sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
          cr * cp * cy + sr * sp * sy};
}

std::array<double, 3> rpy_deg_from_quaternion(const std::array<double, 4>& xyzw) {
  const double n =
      std::sqrt(xyzw[0] * xyzw[0] + xyzw[1] * xyzw[1] + xyzw[2] * xyzw[2] + xyzw[3] * xyzw[3]);
  const double x = xyzw[0] / n, y = xyzw[1] / n, z = xyzw[2] / n, w = xyzw[3] / n;
  const double roll = std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
  const double pitch = std::asin(std::clamp(2.0 * (w * y - z * x), -1.0, 1.0));
  const double yaw = std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  return {roll / kRadPerDeg, pitch / kRadPerDeg, yaw / kRadPerDeg};
}

Extrinsic pose_from_json(const nlohmann::json& value, const std::string& path) {
  if (!value.is_object())
    throw ContractError(path +
                        ": expected a pose {\"xyz_m\": [3], \"rpy_deg\": [3]} or "
                        "{\"translation\": [3], \"rotation_xyzw\": [4]}, got " +
                        json_type_name(value));
  if (value.contains("translation") || value.contains("rotation_xyzw"))
    return Extrinsic::from_json(value, path);
  FieldReader r(value, path);
  r.reject_unknown({"xyz_m", "rpy_deg"});
  Extrinsic out;
  out.translation = finite_numbers<3>(r.at("xyz_m"), r.child("xyz_m"));
  out.rotation_xyzw =
      quaternion_from_rpy_deg(finite_numbers<3>(r.at("rpy_deg"), r.child("rpy_deg")));
  return out;
}

nlohmann::json pose_to_rpy_json(const Extrinsic& pose) {
  return {{"xyz_m", pose.translation}, {"rpy_deg", rpy_deg_from_quaternion(pose.rotation_xyzw)}};
}

std::vector<ExtrinsicOverride> parse_calibration(const nlohmann::json& calibration,
                                                 const std::string& path) {
  std::vector<ExtrinsicOverride> out;
  if (calibration.is_null()) return out;
  if (!calibration.is_object())
    throw ContractError(path +
                        ": expected an object {\"<sensor>\": {\"T_body_sensor\": pose}}, got " +
                        json_type_name(calibration));
  for (const auto& [sensor, keys] : calibration.items()) {
    const std::string sensor_path = path + "." + sensor;
    if (sensor.empty()) throw ContractError(path + ": empty sensor name");
    if (!keys.is_object() || keys.size() != 1)
      throw ContractError(
          sensor_path + ": expected one key, T_body_sensor or T_<reference>_" + sensor + ", got " +
          (keys.is_object() ? std::to_string(keys.size()) + " keys" : json_type_name(keys)));
    ExtrinsicOverride o;
    o.sensor = sensor;
    o.key = keys.begin().key();
    const std::string suffix = "_" + sensor;
    if (o.key == "T_body_sensor") {
      // the body frame
    } else if (o.key.size() > 2 + suffix.size() && o.key.compare(0, 2, "T_") == 0 &&
               o.key.compare(o.key.size() - suffix.size(), suffix.size(), suffix) == 0) {
      o.reference = o.key.substr(2, o.key.size() - 2 - suffix.size());
      if (o.reference == "body") o.reference.clear();
    } else {
      throw ContractError(sensor_path + "." + o.key + ": expected T_body_sensor or T_<reference>_" +
                          sensor);
    }
    if (o.reference == sensor)
      throw ContractError(o.path() + ": a sensor cannot be its own reference");
    o.T_reference_sensor = pose_from_json(keys.begin().value(), sensor_path + "." + o.key);
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace keel::proto
