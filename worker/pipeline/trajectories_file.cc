#include "worker/pipeline/trajectories_file.h"

#include <cmath>
#include <fstream>

#include "worker/pipeline/pose_json.h"
#include "worker/pipeline/report.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;

json entry_json(const TrajectoryEntry& entry) {
  json t = json::array(), xyz = json::array();
  for (const auto& pose : entry.poses) {
    t.push_back(ns_to_seconds(pose.t_ns));
    const Eigen::Vector3d p = pose.T_world_body.translation();
    xyz.push_back({p.x(), p.y(), p.z()});
  }
  json out = {{"name", entry.name}, {"frame", entry.frame}, {"t", t}, {"xyz", xyz}};
  if (!entry.ate_m.empty()) out["ate_m"] = entry.ate_m;  // NaN is written as null
  return out;
}

}  // namespace

std::vector<double> per_pose_ate(const Trajectory& truth, const Trajectory& estimate,
                                 const slam::AssociationOptions& association) {
  const slam::AteResult ate =
      slam::absolute_trajectory_error(truth, estimate, slam::Alignment::kSE3, association);
  // The same association absolute_trajectory_error made, in the same order as its errors.
  const slam::Association pairs = slam::associate_by_time(truth, estimate, association);
  std::vector<double> out(estimate.size(), std::nan(""));
  for (size_t k = 0; k < pairs.estimate_index.size(); ++k)
    out[pairs.estimate_index[k]] = ate.translation_errors_m[k];
  return out;
}

json trajectories_json(const std::vector<TrajectoryEntry>& entries,
                       const std::optional<Pose3>& T_world_model) {
  json out = {{"frame", "world"}};
  if (T_world_model) out["T_world_model"] = pose_to_json(*T_world_model);
  out["trajectories"] = json::array();
  for (const auto& entry : entries) out["trajectories"].push_back(entry_json(entry));
  return out;
}

void add_to_trajectories_file(const std::filesystem::path& work_dir,
                              const std::vector<TrajectoryEntry>& entries,
                              const std::optional<Pose3>& T_world_model) {
  const std::filesystem::path path = work_dir / kTrajectoriesFile;
  json document = trajectories_json(entries, T_world_model);
  std::ifstream in(path);
  json earlier = in ? json::parse(in, nullptr, /*allow_exceptions=*/false) : json(nullptr);
  if (earlier.is_object() && earlier.contains("trajectories") &&
      earlier["trajectories"].is_array()) {
    json merged = json::array();
    for (const auto& old : earlier["trajectories"]) {
      const bool replaced =
          std::any_of(entries.begin(), entries.end(), [&](const TrajectoryEntry& e) {
            return old.is_object() && old.value("name", "") == e.name;
          });
      if (!replaced) merged.push_back(old);
    }
    for (const auto& entry : document["trajectories"]) merged.push_back(entry);
    document["trajectories"] = merged;
    if (!T_world_model && earlier.contains("T_world_model"))
      document["T_world_model"] = earlier["T_world_model"];
  }
  nlohmann::ordered_json ordered = {{"frame", "world"}};
  if (document.contains("T_world_model")) ordered["T_world_model"] = document["T_world_model"];
  ordered["trajectories"] = document["trajectories"];
  write_json_atomically(path, ordered);
}

}  // namespace keel::pipeline
