// Step of the `calibrate` stage: the scans Algorithm 3 (seed 000) works on. For each sensor and
// keyframe K_j, the sensor's scan nearest K_j's time (within half the keyframe spacing),
// deskewed into the sensor frame at its stamp with the body poses, voxel-downsampled, with
// T_world_body at its stamp. Both the automatic refinement and the viewer's calibration page
// (calibration_scans.bin, artifacts.h) place these scans.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/calibrate/artifacts.h"

namespace keel::pipeline {

struct KeyframeScanOptions {
  double scan_voxel_m = 0.05;         // per-scan voxel leaf; keeps a window of scans small
  double max_sweep_duration_s = 1.0;  // as the map stage's deskew check
};

struct SensorToCollect {
  std::string name;
  std::string type;  // "lidar" | "sonar"
  Pose3 T_body_sensor = Pose3::Identity();
  std::string source;  // where the extrinsic came from, carried into the file
};

// `keyframes`: the keyframe stamps (refined or recorded `map`); `T_world_body`: the body poses
// scans are placed and deskewed with (build_poses). Scans outside the poses' span are skipped.
// Throws std::runtime_error naming the sensor and the scan on bad data (as the map stage does).
CalibrationScans collect_keyframe_scans(
    const io::MissionReader& reader, const std::vector<TimeNs>& keyframes,
    const Trajectory& T_world_body, const std::vector<SensorToCollect>& sensors,
    const std::string& reference, const KeyframeScanOptions& options,
    const std::function<void()>& check_canceled = [] {});

}  // namespace keel::pipeline
