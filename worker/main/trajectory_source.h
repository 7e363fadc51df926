// Trajectories named on the command line of `keel-worker ate` / `keel-worker rpe`: a TUM file,
// a KITTI pose file (12 numbers per line, the row-major 3x4 matrix T_world_body; the line index
// is the time in seconds, as evo reads it), or a ROS1 bag topic written BAG:TOPIC
// (geometry_msgs/PoseStamped or nav_msgs/Odometry).
#pragma once

#include <filesystem>
#include <string>

#include "core/pose.h"

namespace keel::worker {

enum class TrajectoryFormat { kTum, kKitti };

// "tum" or "kitti"; throws std::invalid_argument naming the text otherwise.
TrajectoryFormat trajectory_format_from_string(const std::string& text);

struct LoadedTrajectory {
  Trajectory poses;
  std::string source;  // the file, or "topic T of bag B", for messages
};

// `spec` is a file, or BAG:TOPIC for a bag (the first ".bag:" splits path and topic). Bag
// topics ignore `format`. Throws naming the file (and line) or the topic on bad input.
LoadedTrajectory load_trajectory_argument(const std::string& spec, TrajectoryFormat format);

// KITTI poses: pose k is stamped k seconds. Fails naming file and line on a wrong field
// count, a non-number or a rotation block that is not a rotation (|R^T R - I| > 1e-2).
Trajectory read_kitti_poses(const std::filesystem::path& path);

}  // namespace keel::worker
