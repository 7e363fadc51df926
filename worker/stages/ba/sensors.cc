#include "worker/stages/ba/sensors.h"

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "proto/contract_error.h"
#include "worker/pipeline/servo_tray.h"

namespace keel::pipeline {

namespace {

using proto::ContractError;
using proto::SensorType;

const proto::SensorSpec& pick_sensor(const io::MissionReader& reader, const std::string& name,
                                     SensorType type, const std::string& option) {
  const auto& manifest = reader.manifest();
  if (!name.empty()) {
    const proto::SensorSpec* spec = manifest.find_sensor(name);
    if (!spec)
      throw ContractError("options.ba." + option + ": mission has no sensor '" + name + "'");
    if (spec->type != type)
      throw ContractError("options.ba." + option + ": sensor '" + name + "' is a " +
                          proto::to_string(spec->type) + ", expected a " + proto::to_string(type));
    return *spec;
  }
  for (const auto& spec : manifest.sensors)
    if (spec.type == type) return spec;
  throw std::runtime_error("ba: mission.yaml has no " + std::string(proto::to_string(type)) +
                           " sensor (model-assisted BA needs camera, dvl_ranges and servo)");
}

Pose3 require_extrinsic(const io::MissionReader& reader, const std::string& sensor) {
  const std::optional<Pose3> T = reader.extrinsic(sensor);
  if (!T)
    throw std::runtime_error("ba: sensor '" + sensor +
                             "' has no T_body_sensor (neither in mission.yaml nor in /tf_static)");
  return *T;
}

}  // namespace

BaSensors pick_sensors(const io::MissionReader& reader, const BaStageOptions& options) {
  BaSensors s;
  s.camera = &pick_sensor(reader, options.camera_sensor, SensorType::kCamera, "camera_sensor");
  s.dvl =
      &pick_sensor(reader, options.dvl_ranges_sensor, SensorType::kDvlRanges, "dvl_ranges_sensor");
  s.servo = &pick_sensor(reader, options.servo_sensor, SensorType::kServo, "servo_sensor");
  if (options.use_depth) {
    if (!options.depth_sensor.empty()) {
      s.depth = &pick_sensor(reader, options.depth_sensor, SensorType::kDepth, "depth_sensor");
    } else {
      for (const auto& spec : reader.manifest().sensors)
        if (spec.type == SensorType::kDepth && spec.is_stream()) {
          s.depth = &spec;
          break;
        }
    }
  }
  for (const proto::SensorSpec* tray : {s.camera, s.dvl})
    if (tray->mounted_on != s.servo->name)
      throw std::runtime_error(
          "ba: sensor '" + tray->name + "' must ride the servo tray '" + s.servo->name +
          "' (mounted_on: " + (tray->mounted_on.empty() ? "none" : tray->mounted_on) + ")");
  return s;
}

ba::BaRig build_rig(const io::MissionReader& reader, const BaSensors& s) {
  const proto::CameraSpec& cam = *s.camera->camera;
  if (cam.model != proto::CameraModel::kPinhole ||
      std::any_of(cam.distortion.begin(), cam.distortion.end(), [](double k) { return k != 0; }))
    throw std::runtime_error("ba: camera '" + s.camera->name +
                             "' must be a rectified pinhole camera without distortion");
  ba::BaRig rig;
  rig.camera_top = {cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height};
  const Pose3 T_body_servo = require_extrinsic(reader, s.servo->name);
  rig.T_vehicle_servo_zero = T_body_servo;
  rig.servo_axis = tray_axis(*s.servo);
  rig.T_servo_camera = T_body_servo.inverse() * require_extrinsic(reader, s.camera->name);
  rig.T_servo_dvl = T_body_servo.inverse() * require_extrinsic(reader, s.dvl->name);
  return rig;
}

}  // namespace keel::pipeline
