// The body poses scans are placed with (seed 000 Sec. VI-C), for `map` and `calibrate`:
// keyframes from refine's trajectory (when that file exists) or the recorded `map` poses
// correct the recorded high-rate `odometry` by Algorithm 2, so every scan between keyframes
// has a pose; without odometry the keyframes are interpolated, without keyframes the
// odometry is used as recorded.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "core/pose.h"
#include "worker/io/mission_reader.h"

namespace keel::pipeline {

struct Poses {
  Trajectory T_world_body;    // what the TF tree interpolates
  Trajectory slam_keyframes;  // the SLAM system's keyframes (recorded `map`), for the baseline
  nlohmann::json report = nlohmann::json::object();  // report.json's map.poses
};

// `refined_trajectory`: refine's TUM file, used when it exists. `stage` names the caller in
// errors. Throws std::runtime_error when the mission has no poses, or fewer than two.
Poses build_poses(const io::MissionReader& reader, const std::filesystem::path& refined_trajectory,
                  bool odometry_correction, const std::string& stage);

}  // namespace keel::pipeline
