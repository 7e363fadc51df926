#include "worker/stages/map/sensors.h"

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "proto/contract_error.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {
namespace {

using proto::ContractError;
using proto::SensorType;

bool is_mappable_type(SensorType type) {
  return type == SensorType::kLidar || type == SensorType::kSonar;
}

// The sensors `options.sensors` names, or every lidar and sonar with scans.
std::vector<const proto::SensorSpec*> candidates(const proto::MissionManifest& manifest,
                                                 const std::vector<std::string>& listed) {
  std::vector<const proto::SensorSpec*> out;
  if (listed.empty()) {
    for (const auto& spec : manifest.sensors)
      if (is_mappable_type(spec.type) && spec.is_scans()) out.push_back(&spec);
    return out;
  }
  for (size_t k = 0; k < listed.size(); ++k) {
    const std::string& name = listed[k];
    // Listed twice, its scans would go into its map twice.
    if (std::find(listed.begin(), listed.begin() + k, name) != listed.begin() + k)
      throw ContractError("options.map.sensors: '" + name + "' is listed twice");
    const proto::SensorSpec* spec = manifest.find_sensor(name);
    if (!spec) {
      std::vector<std::string> names;
      for (const auto& s : manifest.sensors) names.push_back(s.name);
      throw ContractError("options.map.sensors: mission has no sensor '" + name +
                          "' (it has: " + join_names(names) + ")");
    }
    if (!is_mappable_type(spec->type) || !spec->is_scans())
      throw ContractError("options.map.sensors: sensor '" + name + "' is a " +
                          proto::to_string(spec->type) + ", expected a lidar or sonar with scans");
    out.push_back(spec);
  }
  return out;
}

// map_<a>_preview.drc would be both a's (or the combined map's) preview and b's map.
void check_preview_names(const std::vector<MappedSensor>& mapped) {
  for (const auto& b : mapped) {
    bool clash = b.name == std::string(kCombinedMapName) + "_preview";
    for (const auto& a : mapped) clash = clash || b.name == a.name + "_preview";
    if (clash)
      throw ContractError("sensor '" + b.name + "': map_" + b.name +
                          ".drc would also name a preview; rename the sensor in mission.yaml");
  }
}

// Every sensor_filters entry must name a mapped sensor.
void check_sensor_filters(const nlohmann::json& sensor_filters,
                          const std::vector<MappedSensor>& mapped) {
  std::vector<std::string> names;
  for (const auto& s : mapped) names.push_back(s.name);
  for (const auto& item : sensor_filters.items())
    if (std::find(names.begin(), names.end(), item.key()) == names.end())
      throw ContractError("options.map.sensor_filters." + item.key() +
                          ": no such sensor is mapped (mapped: " + join_names(names) + ")");
}

}  // namespace

SensorSelection select_sensors(const io::MissionReader& reader, const MapStageOptions& options) {
  const bool explicit_list = !options.sensors.empty();
  SensorSelection selection;
  for (const proto::SensorSpec* spec : candidates(reader.manifest(), options.sensors)) {
    // Its files would be the combined map's (map_combined.drc/.ply), written concurrently.
    if (spec->name == kCombinedMapName)
      throw ContractError("sensor '" + spec->name + "': the name is reserved for the combined " +
                          "map (map_" + kCombinedMapName + ".drc); rename the sensor in " +
                          "mission.yaml");
    if (!spec->mounted_on.empty()) {
      selection.skipped.push_back(
          {{"sensor", spec->name},
           {"reason", "rides the servo tray '" + spec->mounted_on +
                          "': its extrinsic varies with the tray angle, and the map's TF tree "
                          "holds static extrinsics only"}});
      continue;
    }
    const std::optional<Pose3> T_body_sensor = reader.extrinsic(spec->name);
    if (!T_body_sensor) {
      const std::string reason =
          "no T_body_sensor (neither in mission.yaml nor in the bag's /tf_static)";
      if (explicit_list) throw std::runtime_error("sensor '" + spec->name + "': " + reason);
      selection.skipped.push_back({{"sensor", spec->name}, {"reason", reason}});
      continue;
    }
    selection.mapped.push_back({spec->name, proto::to_string(spec->type), *T_body_sensor});
  }
  check_preview_names(selection.mapped);
  if (selection.mapped.empty())
    throw std::runtime_error(
        "map: no lidar or sonar scans to map (skipped: " + selection.skipped.dump() + ")");
  check_sensor_filters(options.sensor_filters, selection.mapped);
  return selection;
}

const MappedSensor* find_slam_sensor(const MapStageOptions& options,
                                     const SensorSelection& selection) {
  for (const auto& s : selection.mapped)
    if (options.slam_sensor.empty() ? s.type == "lidar" : s.name == options.slam_sensor) return &s;
  if (!options.slam_sensor.empty())
    throw ContractError("options.map.slam_sensor: '" + options.slam_sensor +
                        "' is not among the mapped sensors");
  return nullptr;
}

}  // namespace keel::pipeline
