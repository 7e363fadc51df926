// A mission bundle on disk: the manifest (mission.yaml) and every path it names, resolved and
// checked to exist (docs/mission-format.md).
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>

#include "proto/mission_manifest.h"

namespace keel::io {

struct Mission {
  std::filesystem::path dir;            // absolute bundle folder
  std::filesystem::path manifest_path;  // dir / mission.yaml
  proto::MissionManifest manifest;
  std::filesystem::path bag_path;  // empty without a bag; a file or a rosbag2 folder
  // By sensor name: the CSV file, or the scans/images folder; absent for bag topics.
  std::map<std::string, std::filesystem::path> sensor_paths;
  // By trajectory name (map, odometry, ground_truth): TUM files; absent for bag topics.
  std::map<std::string, std::filesystem::path> trajectory_paths;
  // By sensor name: packets.calibration (a Velodyne driver YAML); absent without one.
  std::map<std::string, std::filesystem::path> calibration_paths;
  std::filesystem::path loop_closures_path;  // empty when absent
  std::filesystem::path ground_truth_path;   // empty when absent
  std::filesystem::path cad_mesh_path;       // empty when absent
  // By sensor name: the job option that replaced its T_body_sensor in `manifest`
  // ("override T_body_sensor", "override T_lidar_h_sonar"; docs/calibration.md); absent when
  // the extrinsic is mission.yaml's or the bag's /tf_static.
  std::map<std::string, std::string> extrinsic_sources;

  const proto::SensorSpec& sensor(std::string_view name) const { return manifest.sensor(name); }
  // Fails naming the sensor when it has no file/folder (a bag topic).
  const std::filesystem::path& sensor_path(std::string_view name) const;
};

// Reads `dir/mission.yaml`, checks it against the contract and checks that every file and
// folder it names exists inside the bundle (scan and image folders must hold index.csv).
// Errors name mission.yaml, the field path and the missing path, e.g.
// `/m/mission.yaml: sensors[0].file: 'imu.csv' not found (/m/imu.csv)`.
Mission load_mission(const std::filesystem::path& dir);

}  // namespace keel::io
