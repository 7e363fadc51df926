// Step 2 of the `calibrate` stage: the reference sensor S_r and the candidates S_c of
// Algorithm 3 (seed 000), each with the extrinsic this job uses and where it came from.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/calibrate/options.h"

namespace keel::pipeline {

struct CalibrationSensor {
  std::string name;
  std::string type;  // "lidar" | "sonar"
  Pose3 T_body_sensor = Pose3::Identity();
  std::string source;  // "mission.yaml", "/tf_static", "override ..."
};

struct CalibrationSelection {
  CalibrationSensor reference;
  std::vector<CalibrationSensor> candidates;
  nlohmann::json skipped = nlohmann::json::array();  // [{"sensor", "reason"}]
  // Why there is nothing to calibrate (no reference or no candidate found by default); empty
  // otherwise. A job running every stage on a mission with one range sensor is not an error.
  std::string nothing_to_do;
};

// The extrinsic of `sensor` for this job and its source; nullopt without one. The one place
// the stage reads extrinsics (the job's `calibration` overrides enter here).
std::optional<CalibrationSensor> job_extrinsic(const io::MissionReader& reader,
                                               const std::string& sensor);

// Throws proto::ContractError naming the option for an unknown or unsuitable sensor named by
// an option.
CalibrationSelection select_calibration_sensors(const io::MissionReader& reader,
                                                const CalibrateStageOptions& options);

}  // namespace keel::pipeline
