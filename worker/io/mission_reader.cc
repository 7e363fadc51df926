#include "worker/io/mission_reader.h"

#include "worker/io/display_path.h"
#include "worker/io/gnss_csv.h"
#include "worker/io/io_error.h"
#include "worker/io/lidar/velodyne_calibration.h"
#include "worker/io/stream_csv.h"
#include "worker/io/tum.h"

namespace keel::io {

using proto::SensorType;

MissionReader::MissionReader(Mission mission) : mission_(std::move(mission)) {
  if (mission_.bag_path.empty()) return;
  bag_ = open_bag(mission_.bag_path);
  // Every topic mission.yaml names must be in the bag: fail now, naming the field.
  auto check = [&](const std::string& topic, const std::string& field) {
    if (topic.empty()) return;
    try {
      bag_->topic(topic);
    } catch (const IoError& e) {
      throw IoError(display_path(mission_.manifest_path) + ": " + field + ": " + e.what());
    }
  };
  const auto& m = mission_.manifest;
  for (size_t i = 0; i < m.sensors.size(); ++i)
    check(m.sensors[i].topic, "sensors[" + std::to_string(i) + "].topic");
  for (const auto& [name, t] : m.trajectories) check(t.topic, "trajectories." + name + ".topic");
}

MissionReader::~MissionReader() = default;

const proto::SensorSpec& MissionReader::expect(const std::string& sensor, SensorType type) const {
  const proto::SensorSpec* spec = mission_.manifest.find_sensor(sensor);
  if (!spec) (void)mission_.sensor(sensor);  // throws naming the mission's sensors
  if (spec->type != type)
    throw IoError(display_path(mission_.manifest_path) + ": sensor '" + sensor + "' is of type " +
                  proto::to_string(spec->type) + ", not " + proto::to_string(type));
  return *spec;
}

ImuSeries MissionReader::read_imu(const std::string& sensor) const {
  const auto& s = expect(sensor, SensorType::kImu);
  return s.topic.empty() ? read_imu_csv(mission_.sensor_path(sensor)) : bag_->read_imu(s.topic);
}

DvlSeries MissionReader::read_dvl(const std::string& sensor) const {
  const auto& s = expect(sensor, SensorType::kDvl);
  return s.topic.empty() ? read_dvl_csv(mission_.sensor_path(sensor)) : bag_->read_dvl(s.topic);
}

DvlRangesSeries MissionReader::read_dvl_ranges(const std::string& sensor) const {
  expect(sensor, SensorType::kDvlRanges);
  return read_dvl_ranges_csv(mission_.sensor_path(sensor));  // the manifest forbids topics here
}

DepthSeries MissionReader::read_depth(const std::string& sensor) const {
  const auto& s = expect(sensor, SensorType::kDepth);
  if (s.file.empty())
    throw IoError(display_path(mission_.manifest_path) + ": sensor '" + sensor +
                  "' holds depth-camera scans, not a pressure-depth CSV (use open_scans)");
  return read_depth_csv(mission_.sensor_path(sensor));
}

ServoSeries MissionReader::read_servo(const std::string& sensor) const {
  expect(sensor, SensorType::kServo);
  return read_servo_csv(mission_.sensor_path(sensor));
}

GnssSeries MissionReader::read_gnss(const std::string& sensor) const {
  const auto& s = expect(sensor, SensorType::kGnss);
  return s.topic.empty() ? read_gnss_csv(mission_.sensor_path(sensor)) : bag_->read_gnss(s.topic);
}

ScanReadOptions MissionReader::scan_options(const std::string& sensor) const {
  const auto& s = mission_.sensor(sensor);
  ScanReadOptions options;
  options.point_time = s.point_time;
  options.sweep_period_s = 1.0 / s.rate_hz;
  options.frame = s.name;
  if (s.packets) {
    // Raw packets: the model's firing table with the driver's calibration, or its factory one.
    const std::string field = display_path(mission_.manifest_path) + ": sensor '" + s.name +
                              "' packets";
    const auto model = lidar::velodyne_model_from_string(s.packets->model, field + ".model");
    const auto path = mission_.calibration_paths.find(s.name);
    options.packets = std::make_shared<const lidar::VelodyneCalibration>(
        path == mission_.calibration_paths.end()
            ? lidar::factory_calibration(model)
            : lidar::load_velodyne_calibration(path->second, model));
  }
  return options;
}

std::unique_ptr<ScanSource> MissionReader::open_scans(const std::string& sensor) const {
  const auto& s = mission_.sensor(sensor);
  if (!s.is_scans())
    throw IoError(display_path(mission_.manifest_path) + ": sensor '" + sensor + "' (" +
                  proto::to_string(s.type) + ") has no scans");
  if (!s.topic.empty()) return bag_->open_scans(s.topic, scan_options(sensor));
  return std::make_unique<ScanFolderReader>(mission_.sensor_path(sensor), scan_options(sensor));
}

std::unique_ptr<ImageSource> MissionReader::open_images(const std::string& sensor) const {
  const auto& s = expect(sensor, SensorType::kCamera);
  if (!s.topic.empty()) return bag_->open_images(s.topic);
  return std::make_unique<ImageFolderReader>(mission_.sensor_path(sensor));
}

bool MissionReader::has_trajectory(const std::string& name) const {
  return mission_.manifest.trajectories.count(name) > 0;
}

Trajectory MissionReader::read_trajectory(const std::string& name) const {
  const auto it = mission_.manifest.trajectories.find(name);
  if (it == mission_.manifest.trajectories.end())
    throw IoError(display_path(mission_.manifest_path) + ": no trajectory '" + name +
                  "' under trajectories");
  if (!it->second.topic.empty()) return bag_->read_trajectory(it->second.topic);
  return read_tum(mission_.trajectory_paths.at(name));
}

std::vector<LoopClosure> MissionReader::read_loop_closures() const {
  if (mission_.loop_closures_path.empty()) return {};
  return io::read_loop_closures(mission_.loop_closures_path);
}

std::optional<Pose3> MissionReader::extrinsic(const std::string& sensor) const {
  const auto& s = mission_.sensor(sensor);
  if (s.T_body_sensor) {
    const auto& q = s.T_body_sensor->rotation_xyzw;
    const auto& t = s.T_body_sensor->translation;
    return make_pose(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
  }
  if (!bag_) return std::nullopt;
  if (!tf_static_) tf_static_ = bag_->read_static_transforms("/tf_static");
  Pose3 T_body_sensor;
  if (lookup_static_transform(*tf_static_, mission_.manifest.body_frame, s.effective_frame(),
                              T_body_sensor))
    return T_body_sensor;
  return std::nullopt;
}

}  // namespace keel::io
