// trajectories.json: the trajectories a viewer draws (docs/artifacts.md), written by `refine`
// (recorded MAP poses, refined, refined without DVL, ground truth; each estimate with its
// per-pose ATE) and by `ba` (its keyframe trajectory in the CAD model frame), each stage adding
// its entries to the file the earlier stages left in the work folder.
//
//   {"frame": "world",                     // the frame of entries that do not name theirs
//    "T_world_model": {...},               // x_gM of the ba stage's solution, when ba ran
//    "trajectories": [{"name", "frame", "t": [s], "xyz": [[x, y, z]], "ate_m": [m]}]}
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::pipeline {

inline constexpr const char* kTrajectoriesFile = "trajectories.json";

struct TrajectoryEntry {
  std::string name;             // recorded | refined | refined_no_dvl | ground_truth | ba
  std::string frame = "world";  // world | model
  Trajectory poses;
  std::vector<double> ate_m;  // empty, or one per pose (NaN: no ground-truth pose associated)
};

// Each estimate pose's translation error after the SE(3) alignment of the report's ATE
// (slam::absolute_trajectory_error over the poses associated by time within `association`),
// NaN for a pose no ground-truth pose associates with. The root mean square of the finite
// values is the report's ATE translation RMSE. Throws as absolute_trajectory_error does.
std::vector<double> per_pose_ate(const Trajectory& truth, const Trajectory& estimate,
                                 const slam::AssociationOptions& association);

// The document of `entries` (pure).
nlohmann::json trajectories_json(const std::vector<TrajectoryEntry>& entries,
                                 const std::optional<Pose3>& T_world_model = std::nullopt);

// Adds `entries` to work_dir/trajectories.json (replacing entries of the same name, keeping the
// others in order; a file that does not parse is replaced) and sets T_world_model when given.
// Writes atomically; throws std::runtime_error naming the file.
void add_to_trajectories_file(const std::filesystem::path& work_dir,
                              const std::vector<TrajectoryEntry>& entries,
                              const std::optional<Pose3>& T_world_model = std::nullopt);

}  // namespace keel::pipeline
