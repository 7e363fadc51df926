#include "worker/stages/refine/evaluation.h"

#include <optional>
#include <stdexcept>
#include <vector>

#include "worker/pipeline/trajectories_file.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;

json metrics_json(const slam::ErrorStatistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"count", s.count}};
}

slam::AssociationOptions association(const RefineStageOptions& options) {
  slam::AssociationOptions a;
  a.max_difference_s = options.ate_max_time_difference_s;
  return a;
}

// ATE and RPE of one estimate against ground truth.
json evaluate(const Trajectory& truth, const Trajectory& estimate,
              const RefineStageOptions& options) {
  const auto ate =
      slam::absolute_trajectory_error(truth, estimate, slam::Alignment::kSE3, association(options));
  slam::RpeOptions rpe_options;
  rpe_options.delta = options.rpe_delta_m;
  rpe_options.unit = slam::DeltaUnit::kMeters;
  rpe_options.pairs_from_reference = true;  // the same pairs for every estimate
  json out = {{"ate",
               {{"translation_m", metrics_json(ate.translation_m)},
                {"rotation_deg", metrics_json(ate.rotation_deg)}}}};
  try {
    const auto rpe = slam::relative_pose_error(truth, estimate, rpe_options, association(options));
    out["rpe"] = {{"translation_m", metrics_json(rpe.translation_m)},
                  {"rotation_deg", metrics_json(rpe.rotation_deg)}};
  } catch (const std::invalid_argument& e) {
    out["rpe"] = {{"error", e.what()}};  // e.g. a path shorter than delta
  }
  return out;
}

std::string ground_truth_source(const io::Mission& mission) {
  const auto& spec = mission.manifest.trajectories.at("ground_truth");
  return spec.topic.empty() ? spec.file : "topic " + spec.topic;
}

}  // namespace

json evaluation_json(const Trajectory& truth, const Trajectory& map_poses,
                     const Trajectory* without_dvl, const Trajectory* with_dvl,
                     const RefineStageOptions& options, const io::Mission& mission) {
  json rows = json::object();
  rows["map"] = evaluate(truth, map_poses, options);
  rows["refined_without_dvl"] =
      without_dvl ? evaluate(truth, *without_dvl, options) : json(nullptr);
  rows["refined_with_dvl"] = with_dvl ? evaluate(truth, *with_dvl, options) : json(nullptr);
  json out = {{"ground_truth", ground_truth_source(mission)},
              {"ate_method",
               "SE(3) Umeyama alignment (Zhang & Scaramuzza 2018, as evo -a); poses associated "
               "by nearest stamp within " +
                   std::to_string(options.ate_max_time_difference_s) + " s"},
              {"rpe_method", "consecutive pose pairs " + std::to_string(options.rpe_delta_m) +
                                 " m apart along the ground-truth path (delta unit: metres)"},
              {"table", rows}};
  auto ate_rmse = [&](const char* row) -> std::optional<double> {
    if (rows[row].is_null()) return std::nullopt;
    return rows[row]["ate"]["translation_m"]["rmse"].get<double>();
  };
  const auto map = ate_rmse("map"), with = ate_rmse("refined_with_dvl"),
             without = ate_rmse("refined_without_dvl");
  if (map && with && *map > 0.0)
    out["ate_reduction_with_dvl_vs_map_percent"] = 100.0 * (1.0 - *with / *map);
  if (map && without && *map > 0.0)
    out["ate_reduction_without_dvl_vs_map_percent"] = 100.0 * (1.0 - *without / *map);
  return out;
}

void write_trajectories(const std::filesystem::path& work_dir, const Trajectory& recorded,
                        const Trajectory& refined, const Trajectory* refined_no_dvl,
                        const Trajectory& truth, const RefineStageOptions& options) {
  auto entry = [&](const std::string& name, const Trajectory& poses) {
    TrajectoryEntry e{name, "world", poses, {}};
    if (!truth.empty()) e.ate_m = per_pose_ate(truth, poses, association(options));
    return e;
  };
  std::vector<TrajectoryEntry> entries = {entry("recorded", recorded), entry("refined", refined)};
  if (refined_no_dvl) entries.push_back(entry("refined_no_dvl", *refined_no_dvl));
  if (!truth.empty()) entries.push_back({"ground_truth", "world", truth, {}});
  add_to_trajectories_file(work_dir, entries);
}

}  // namespace keel::pipeline
