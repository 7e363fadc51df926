#include "worker/stages/calibrate/sensors.h"

#include <algorithm>
#include <stdexcept>

#include "proto/contract_error.h"

namespace keel::pipeline {
namespace {

using proto::ContractError;
using proto::SensorSpec;
using proto::SensorType;

bool is_range_scanner(const SensorSpec& spec) {
  return (spec.type == SensorType::kLidar || spec.type == SensorType::kSonar) && spec.is_scans();
}

std::vector<std::string> sensor_names(const proto::MissionManifest& manifest) {
  std::vector<std::string> names;
  for (const auto& s : manifest.sensors) names.push_back(s.name);
  return names;
}

// A sensor named by an option: it exists, is a lidar or sonar with scans, has an extrinsic.
CalibrationSensor named_sensor(const io::MissionReader& reader, const std::string& name,
                               const std::string& path) {
  const SensorSpec* spec = reader.manifest().find_sensor(name);
  if (!spec)
    throw ContractError(path + ": mission has no sensor '" + name +
                        "' (it has: " + join_names(sensor_names(reader.manifest())) + ")");
  if (!is_range_scanner(*spec))
    throw ContractError(path + ": sensor '" + name + "' is a " + proto::to_string(spec->type) +
                        ", expected a lidar or sonar with scans");
  if (!spec->mounted_on.empty())
    throw ContractError(path + ": sensor '" + name + "' rides the servo tray '" + spec->mounted_on +
                        "': its extrinsic varies with the tray angle");
  const auto sensor = job_extrinsic(reader, name);
  if (!sensor)
    throw ContractError(path + ": sensor '" + name +
                        "' has no T_body_sensor (neither in mission.yaml nor in the bag's "
                        "/tf_static)");
  return *sensor;
}

}  // namespace

std::optional<CalibrationSensor> job_extrinsic(const io::MissionReader& reader,
                                               const std::string& sensor) {
  const SensorSpec* spec = reader.manifest().find_sensor(sensor);
  const std::optional<Pose3> T_body_sensor = reader.extrinsic(sensor);
  if (!spec || !T_body_sensor) return std::nullopt;
  // The job's override when it has one (pipeline/job_extrinsics.h), else mission.yaml's or
  // the bag's.
  const auto& overrides = reader.mission().extrinsic_sources;
  const auto source = overrides.find(sensor);
  return CalibrationSensor{sensor, proto::to_string(spec->type), *T_body_sensor,
                           source != overrides.end() ? source->second
                           : spec->T_body_sensor ? "mission.yaml"
                                                 : "/tf_static"};
}

CalibrationSelection select_calibration_sensors(const io::MissionReader& reader,
                                                const CalibrateStageOptions& options) {
  const proto::MissionManifest& manifest = reader.manifest();
  CalibrationSelection selection;
  if (!options.reference.empty()) {
    selection.reference = named_sensor(reader, options.reference, "options.calibrate.reference");
  } else {
    const auto first =
        std::find_if(manifest.sensors.begin(), manifest.sensors.end(), [&](const SensorSpec& s) {
          return s.type == SensorType::kLidar && is_range_scanner(s) && s.mounted_on.empty() &&
                 job_extrinsic(reader, s.name);
        });
    if (first == manifest.sensors.end()) {
      selection.nothing_to_do =
          "the mission has no lidar with scans and an extrinsic to calibrate against";
      return selection;
    }
    selection.reference = *job_extrinsic(reader, first->name);
  }

  if (!options.candidates.empty()) {
    for (size_t k = 0; k < options.candidates.size(); ++k) {
      const std::string& name = options.candidates[k];
      const std::string path = "options.calibrate.candidates";
      if (name == selection.reference.name)
        throw ContractError(path + ": '" + name + "' is the reference sensor");
      if (std::count(options.candidates.begin(), options.candidates.begin() + k, name) > 0)
        throw ContractError(path + ": '" + name + "' is listed twice");
      selection.candidates.push_back(named_sensor(reader, name, path));
    }
    return selection;
  }
  for (const SensorSpec& spec : manifest.sensors) {
    if (!is_range_scanner(spec) || spec.name == selection.reference.name) continue;
    if (!spec.mounted_on.empty()) {
      selection.skipped.push_back({{"sensor", spec.name},
                                   {"reason", "rides the servo tray '" + spec.mounted_on +
                                                  "': its extrinsic varies with the tray angle"}});
      continue;
    }
    const auto sensor = job_extrinsic(reader, spec.name);
    if (!sensor) {
      selection.skipped.push_back(
          {{"sensor", spec.name},
           {"reason", "no T_body_sensor (neither in mission.yaml nor in the bag's /tf_static)"}});
      continue;
    }
    selection.candidates.push_back(*sensor);
  }
  if (selection.candidates.empty())
    selection.nothing_to_do =
        "no lidar or sonar with scans and an extrinsic besides the reference '" +
        selection.reference.name + "'";
  return selection;
}

}  // namespace keel::pipeline
