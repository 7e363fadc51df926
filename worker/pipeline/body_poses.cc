#include "worker/pipeline/body_poses.h"

#include <stdexcept>
#include <string>

#include "worker/io/tum.h"
#include "worker/mapping/odometry_correction.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json span_json(const Trajectory& poses) {
  if (poses.empty()) return {{"poses", 0}};
  return {{"poses", poses.size()},
          {"t_first_s", ns_to_seconds(poses.front().t_ns)},
          {"t_last_s", ns_to_seconds(poses.back().t_ns)},
          {"duration_s", ns_to_seconds(poses.back().t_ns - poses.front().t_ns)}};
}

// The keyframe poses: the refined trajectory, else the recorded `map` poses, else none.
Trajectory read_keyframes(const io::MissionReader& reader, const fs::path& refined_path,
                          json& report) {
  std::error_code ec;
  Trajectory keyframes;
  if (fs::is_regular_file(refined_path, ec)) {
    keyframes = io::read_tum(refined_path);
    report["keyframes"] = span_json(keyframes);
    report["keyframes"]["source"] = refined_path.filename().string();
  } else if (reader.has_trajectory("map")) {
    keyframes = reader.read_trajectory("map");
    report["keyframes"] = span_json(keyframes);
    report["keyframes"]["source"] = "trajectories.map (recorded)";
  }
  return keyframes;
}

}  // namespace

Poses build_poses(const io::MissionReader& reader, const fs::path& refined_trajectory,
                  bool odometry_correction, const std::string& stage) {
  Poses poses;
  const Trajectory keyframes = read_keyframes(reader, refined_trajectory, poses.report);
  if (reader.has_trajectory("map")) poses.slam_keyframes = reader.read_trajectory("map");

  const bool has_odometry = reader.has_trajectory("odometry");
  if (keyframes.empty()) {
    if (!has_odometry)
      throw std::runtime_error(stage + " needs poses: no " +
                               refined_trajectory.filename().string() +
                               " from a refine stage, and mission.yaml has "
                               "neither trajectories.map nor trajectories.odometry");
    poses.T_world_body = reader.read_trajectory("odometry");
    poses.report["keyframes"] = nullptr;
    poses.report["source"] = "trajectories.odometry as recorded (no keyframe poses to correct it)";
  } else if (has_odometry && odometry_correction) {
    const Trajectory odometry = reader.read_trajectory("odometry");
    const mapping::OdometryCorrection correction = mapping::correct_odometry(keyframes, odometry);
    poses.T_world_body = correction.refined;
    poses.report["odometry"] = span_json(odometry);
    poses.report["source"] =
        "trajectories.odometry corrected by the keyframe poses (Algorithm 2, seed 000)";
    poses.report["correction"] = {
        {"corrections", correction.corrections.size()},
        {"keyframes_outside_odometry", correction.map_poses_outside_odometry},
        {"odometry_poses_dropped", correction.odometry_poses_dropped}};
  } else {
    poses.T_world_body = keyframes;
    poses.report["source"] = has_odometry
                                 ? "keyframe poses, interpolated (odometry_correction = false)"
                                 : "keyframe poses, interpolated (mission has no odometry)";
  }
  if (poses.slam_keyframes.empty()) poses.slam_keyframes = keyframes;
  if (poses.T_world_body.size() < 2)
    throw std::runtime_error(stage + " needs at least 2 poses to interpolate, found " +
                             std::to_string(poses.T_world_body.size()));
  poses.report["trajectory"] = span_json(poses.T_world_body);
  return poses;
}

}  // namespace keel::pipeline
