// Reads a mission's data whatever the source: CSV/TUM/PCD/PLY/PNG files or bag topics, as
// mission.yaml says (bags: ROS1, or ROS 2 as a rosbag2 folder or one .mcap/.db3 file). Downstream
// code asks for a sensor by name and gets typed values.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/io/bag/bag_source.h"
#include "worker/io/image_source.h"
#include "worker/io/loop_closures.h"
#include "worker/io/mission.h"
#include "worker/io/scan_source.h"
#include "worker/io/stream_samples.h"

namespace keel::io {

class MissionReader {
 public:
  // Opens the bag when the mission has one (fails naming it when it is truncated).
  explicit MissionReader(Mission mission);
  ~MissionReader();

  const Mission& mission() const { return mission_; }
  const proto::MissionManifest& manifest() const { return mission_.manifest; }
  const BagSource* bag() const { return bag_.get(); }

  // Each fails naming the sensor when it is not of that type, and the file/topic on bad data.
  ImuSeries read_imu(const std::string& sensor) const;
  DvlSeries read_dvl(const std::string& sensor) const;
  DvlRangesSeries read_dvl_ranges(const std::string& sensor) const;
  DepthSeries read_depth(const std::string& sensor) const;  // pressure depth (a `file:` sensor)
  ServoSeries read_servo(const std::string& sensor) const;
  // Every fix, no-fix ones included (status -1): a CSV (gnss_csv.h) or sensor_msgs/NavSatFix.
  GnssSeries read_gnss(const std::string& sensor) const;
  // Scan sensors (lidar, sonar, depth with scans); the time field per the manifest's
  // point_time, checked against 10 sweep periods (1 / rate_hz).
  std::unique_ptr<ScanSource> open_scans(const std::string& sensor) const;
  std::unique_ptr<ImageSource> open_images(const std::string& sensor) const;

  bool has_trajectory(const std::string& name) const;
  // `name` is map, odometry or ground_truth.
  Trajectory read_trajectory(const std::string& name) const;
  std::vector<LoopClosure> read_loop_closures() const;  // empty without loop_closures

  // T_body_sensor from mission.yaml, else from the bag's /tf_static (body_frame -> the
  // sensor's frame_id); nothing when neither has it.
  std::optional<Pose3> extrinsic(const std::string& sensor) const;
  ScanReadOptions scan_options(const std::string& sensor) const;

 private:
  const proto::SensorSpec& expect(const std::string& sensor, proto::SensorType type) const;

  Mission mission_;
  std::unique_ptr<BagSource> bag_;
  mutable std::optional<std::vector<StaticTransform>> tf_static_;
};

}  // namespace keel::io
