// The extrinsics a job uses: mission.yaml's T_body_sensor, else the bag's /tf_static, each
// replaced by the job's `calibration` override when it has one (docs/calibration.md, section
// 1). Every stage loads its mission through load_job_mission, so one override reaches them all
// (io::MissionReader::extrinsic and the manifest's T_body_sensor both return it).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>

#include "core/pose.h"
#include "worker/io/mission.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {

struct SensorExtrinsic {
  Pose3 T_body_sensor = Pose3::Identity();
  // "mission.yaml", "/tf_static", "override T_body_sensor", "override T_lidar_h_sonar"
  std::string source;
};
using JobExtrinsics = std::map<std::string, SensorExtrinsic>;  // by sensor name

// io::load_mission, then the overrides of `calibration` (the job options' "calibration"
// object; null: none) written into the manifest's T_body_sensor, and their sources into
// Mission::extrinsic_sources. A relative override T_<reference>_<sensor> is composed with the
// reference's own extrinsic (its T_body_sensor override, mission.yaml's, or /tf_static's):
// T_body_sensor = T_body_reference * T_reference_sensor. Throws proto::ContractError naming
// the option path and the sensor (`calibration.sonr: no sensor 'sonr' in the mission
// (sensors: imu, dvl, ...)`).
io::Mission load_job_mission(const std::filesystem::path& mission_dir,
                             const nlohmann::json& calibration);
// The same for a stage: context.mission_dir with context.calibration.
io::Mission load_job_mission(const StageContext& context);

// Per sensor with an extrinsic, the T_body_sensor the job uses and where it came from.
// `reader` reads a mission of load_job_mission.
JobExtrinsics job_extrinsics(const io::MissionReader& reader);
// The same without a reader at hand: opens the bag only when a sensor's extrinsic can come
// from nowhere else.
JobExtrinsics job_extrinsics(const io::Mission& mission);

// report.json's top-level `calibration` section: {"<sensor>": {"source": ..., "T_body_sensor":
// {"translation", "rotation_xyzw"}, "xyz_m": [..], "rpy_deg": [..]}} in sensor-name order.
nlohmann::json calibration_report(const JobExtrinsics& extrinsics);

}  // namespace keel::pipeline
