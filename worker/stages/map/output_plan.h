// Steps 5 and 6 of the map stage as output tasks (OutputRunner): each sensor map's LOD tiles,
// PLY file and Draco file (with its preview), the metrics of the SLAM map and of the SLAM
// lidar's inspection map, and the same for the combined map (Eq. (21)), which is kept as its
// parts, the sensor maps, never copied whole. A sensor's tasks start on one extra thread as
// soon as its last scan is in, while the next sensors scan; the rest run costliest first on
// `threads` threads once every map is built, as many side by side as the budget's output
// share allows (output_costs.h). Each task writes its result into a slot made before any task
// runs; a Draco file that would not fit the budget is not made, and a warning says so.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "worker/pipeline/stage.h"
#include "worker/stages/map/map_draco.h"
#include "worker/stages/map/map_outputs.h"
#include "worker/stages/map/metrics.h"
#include "worker/stages/map/options.h"
#include "worker/stages/map/output_runner.h"
#include "worker/stages/map/scan_pass.h"

namespace keel::pipeline {

class OutputPlan {
 public:
  // Task lines in the job log count from `origin`. The arguments must outlive the plan.
  OutputPlan(const MapStageOptions& options, ScanPass& scans, StageContext& context,
             nlohmann::json& warnings, std::chrono::steady_clock::time_point origin);
  // Joins the tasks; unless keep() was called, removes every map file they wrote, so none can
  // pass for a finished map after a failure.
  ~OutputPlan();
  OutputPlan(const OutputPlan&) = delete;
  OutputPlan& operator=(const OutputPlan&) = delete;

  // From now on one thread runs the tasks of the sensors started, beside the scans.
  void run_beside_scans();
  // Throws the first failure of a task so far (the scans then stop).
  void rethrow_if_failed();
  // Queues the tasks of a sensor whose map is complete (and the SLAM map's, for its lidar).
  void start_sensor(const std::string& name);
  // Queues every task not started yet and the combined map's, runs them on `threads` threads
  // and waits for them all. Throws when every map is empty.
  void run_rest();
  // The files and report sections of the sensor maps `written` (largest first) and of the
  // combined map.
  void collect(const std::vector<std::string>& written, StageResult& out);

  const MetricsColumns& metrics() const { return metrics_; }
  double budget_bytes() const { return budget_bytes_; }
  // The stage succeeded: its files stay; the tasks' lines go to the job log.
  void keep();

 private:
  std::vector<OutputTask> sensor_tasks(const std::string& name);
  std::vector<OutputTask> slam_tasks();
  std::vector<OutputTask> combined_tasks();
  OutputTask combined_draco_check();
  // Tasks that first check for a cancel request, so a canceled job starts no further output.
  std::vector<OutputTask> guarded(std::vector<OutputTask> tasks) const;
  std::function<void()> cancel_check() const;
  double tile_bytes() const;
  bool is_slam_sensor(const std::string& name) const;

  const MapStageOptions& options_;
  ScanPass& scans_;
  StageContext& context_;
  nlohmann::json& warnings_;
  const double budget_bytes_;         // what the tasks may hold at once
  std::vector<std::string> started_;  // sensors whose tasks started during the scans
  bool slam_started_ = false;
  std::map<std::string, MapOutput> drc_, ply_, tiles_, preview_;  // by sensor
  MapOutput combined_drc_, combined_ply_, combined_tiles_, combined_preview_;
  std::vector<std::string> combined_parts_;  // the sensor maps of the combined map
  size_t combined_points_ = 0;
  std::optional<CombinedDraco> combined_draco_;
  MetricsColumns metrics_;
  bool keep_ = false;
  TaskLog task_log_;
  std::optional<OutputRunner> runner_;  // last: joins the tasks before what they use goes
};

}  // namespace keel::pipeline
