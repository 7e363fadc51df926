// Step 2 of the map stage: the scan sensors to map. Every lidar and sonar with scans unless
// `sensors` names them; a sensor on a servo tray (`mounted_on`) is skipped, because its
// extrinsic varies with the tray angle and MapBuilder's TF tree holds static extrinsics.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/map/options.h"

namespace keel::pipeline {

struct MappedSensor {
  std::string name;
  std::string type;  // "lidar" | "sonar"
  Pose3 T_body_sensor = Pose3::Identity();
};

struct SensorSelection {
  std::vector<MappedSensor> mapped;                  // names unique, in the mission's order
  nlohmann::json skipped = nlohmann::json::array();  // [{sensor, reason}]
};

// Throws ContractError for a sensor that cannot be mapped as named (unknown, not a scan
// sensor, listed twice, a name its files would share with another map's) and for a
// `sensor_filters` entry naming no mapped sensor; std::runtime_error for a sensor named
// without extrinsic, and when nothing is left to map.
SensorSelection select_sensors(const io::MissionReader& reader, const MapStageOptions& options);

// The lidar whose keyframe scans build the SLAM-map baseline: `slam_sensor`, else the first
// lidar mapped; nullptr when no lidar is mapped.
const MappedSensor* find_slam_sensor(const MapStageOptions& options,
                                     const SensorSelection& selection);

}  // namespace keel::pipeline
