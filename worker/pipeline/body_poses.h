// Step 3 of the map stage: the poses of Sec. VI-C (seed 000). Keyframes from
// `trajectory_refined.tum` (an earlier `refine`) or the recorded `map` poses correct the
// recorded high-rate `odometry` by Algorithm 2, so every scan between keyframes has a pose;
// without odometry the keyframes are interpolated, without keyframes the odometry is used as
// recorded.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/pose.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/map/options.h"

namespace keel::pipeline {

struct Poses {
  Trajectory T_world_body;    // what the TF tree interpolates
  Trajectory slam_keyframes;  // the SLAM system's keyframes (recorded `map`), for the baseline
  nlohmann::json report = nlohmann::json::object();  // report.json's map.poses
};

// Throws std::runtime_error when the mission has no poses to map with, or fewer than two.
Poses build_poses(const io::MissionReader& reader, const MapStageOptions& options,
                  const std::filesystem::path& work_dir);

}  // namespace keel::pipeline
