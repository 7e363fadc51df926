#include "worker/stages/map/output_plan.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "worker/stages/map/artifacts.h"
#include "worker/stages/map/output_costs.h"

namespace keel::pipeline {

namespace fs = std::filesystem;

OutputPlan::OutputPlan(const MapStageOptions& options, ScanPass& scans, StageContext& context,
                       nlohmann::json& warnings, std::chrono::steady_clock::time_point origin)
    : options_(options),
      scans_(scans),
      context_(context),
      warnings_(warnings),
      budget_bytes_(output_budget_bytes(options)),
      task_log_(origin, "map: output task") {
  for (const auto& s : scans.selection().mapped) {
    drc_[s.name];
    ply_[s.name];
    tiles_[s.name];
    preview_[s.name];
  }
  runner_.emplace(task_log_);
}

OutputPlan::~OutputPlan() {
  runner_.reset();
  if (keep_) return;
  std::vector<const MapOutput*> outputs = {&combined_drc_, &combined_ply_, &combined_tiles_,
                                           &combined_preview_};
  for (const auto* by_sensor : {&drc_, &ply_, &tiles_, &preview_})
    for (const auto& [name, output] : *by_sensor) outputs.push_back(&output);
  std::error_code ignored;  // best effort: the stage's own error is the one to report
  for (const MapOutput* output : outputs)
    for (const auto& file : output->artifacts) fs::remove(context_.work_dir / file, ignored);
}

void OutputPlan::run_beside_scans() { runner_->run_with(1, 0.0); }

void OutputPlan::rethrow_if_failed() { runner_->rethrow_if_failed(); }

void OutputPlan::start_sensor(const std::string& name) {
  if (scans_.has_scans(name)) {
    runner_->add(guarded(sensor_tasks(name)));
    started_.push_back(name);
  }
  if (is_slam_sensor(name)) {
    runner_->add(guarded(slam_tasks()));
    slam_started_ = true;
  }
}

void OutputPlan::run_rest() {
  const std::vector<std::string> built = scans_.built();
  for (const auto& name : built) {
    if (scans_.map_points(name) == 0) continue;
    combined_parts_.push_back(name);
    combined_points_ += scans_.map_points(name);
  }
  if (combined_points_ == 0) throw std::runtime_error("map: every map is empty; nothing to write");

  std::vector<OutputTask> tasks;
  for (const auto& name : built) {
    if (std::find(started_.begin(), started_.end(), name) != started_.end()) continue;
    for (auto& task : sensor_tasks(name)) tasks.push_back(std::move(task));
  }
  if (scans_.slam() && !slam_started_)
    for (auto& task : slam_tasks()) tasks.push_back(std::move(task));
  for (auto& task : combined_tasks()) tasks.push_back(std::move(task));
  runner_->add(guarded(std::move(tasks)));
  // Tile tasks hold a tile per thread, a Draco task its whole map.
  runner_->run_with(options_.threads, budget_bytes_);
  try {
    runner_->finish([&](double f) { context_.progress(kScansDone + (1.0 - kScansDone) * f); });
  } catch (const TileBudgetError& e) {
    throw_memory_budget_error(e, options_);
  }
  context_.check_canceled();
}

std::vector<OutputTask> OutputPlan::guarded(std::vector<OutputTask> tasks) const {
  for (auto& task : tasks)
    task.run = [&context = context_, run = std::move(task.run)] {
      context.check_canceled();
      run();
    };
  return tasks;
}

std::function<void()> OutputPlan::cancel_check() const {
  return [this] { context_.check_canceled(); };
}

double OutputPlan::tile_bytes() const {
  return static_cast<double>(scans_.tiled().options().tile_budget_bytes);
}

bool OutputPlan::is_slam_sensor(const std::string& name) const {
  return scans_.slam() && name == scans_.slam_sensor()->name;
}

// Each task reads the map's tiles, but the Draco file's, which gathers the map in memory.
std::vector<OutputTask> OutputPlan::sensor_tasks(const std::string& name) {
  std::vector<OutputTask> tasks;
  const size_t n = scans_.map_points(name);
  if (n == 0) return tasks;
  TiledMaps& tiled = scans_.tiled();
  if (draco_bytes(n, options_) <= budget_bytes_) {
    tasks.push_back({"draco " + name, draco_seconds(n, kDracoSecondsPerPoint, options_),
                     draco_bytes(n, options_), [this, &tiled, name, n] {
                       write_sensor_draco(tiled, name, n, options_, context_.work_dir,
                                          cancel_check(), drc_.at(name), preview_.at(name));
                     }});
  } else {
    drc_.at(name) = draco_not_written(n, draco_bytes(n, options_), budget_bytes_);
    warnings_.push_back("sensor '" + name +
                        "': " + drc_.at(name).report["draco"]["reason"].get<std::string>());
  }
  if (options_.write_ply)
    tasks.push_back({"ply " + name, kPlySecondsPerPoint * n, tile_bytes(), [this, &tiled, name] {
                       ply_.at(name) = write_tiled_map_ply(tiled, {name}, name, context_.work_dir,
                                                           cancel_check());
                     }});
  if (options_.write_tiles)
    tasks.push_back({"tiles " + name, kLodSecondsPerPoint * n, tile_bytes(), [this, &tiled, name] {
                       tiles_.at(name) =
                           write_map_tiles(tiled, {name}, name, context_.work_dir, cancel_check());
                     }});
  if (is_slam_sensor(name))
    tasks.push_back({"metrics inspection_" + name, kMetricsSecondsPerPoint * n,
                     tile_bytes() * options_.threads, [this, &tiled, name] {
                       metrics_.inspection = measure_tiled("inspection_" + name, tiled, {name},
                                                           options_, cancel_check());
                     }});
  return tasks;
}

std::vector<OutputTask> OutputPlan::slam_tasks() {
  std::vector<OutputTask> tasks;
  if (scans_.slam_points() > 0)
    tasks.push_back({"metrics slam_map", kMetricsSecondsPerPoint * scans_.slam_points(),
                     tile_bytes() * options_.threads, [this] {
                       metrics_.slam_map = measure_tiled("slam_map", scans_.tiled(), {"slam"},
                                                         options_, cancel_check());
                     }});
  return tasks;
}

// The combined map's Draco file is encoded in one task, which then queues its check.
std::vector<OutputTask> OutputPlan::combined_tasks() {
  std::vector<OutputTask> tasks;
  const size_t n = combined_points_;
  TiledMaps& tiled = scans_.tiled();
  if (draco_bytes(n, options_) <= budget_bytes_) {
    combined_draco_.emplace(tiled, combined_parts_, n, options_, context_.work_dir);
    tasks.push_back({"draco combined (encode)",
                     draco_seconds(n, kDracoEncodeSecondsPerPoint, options_),
                     draco_bytes(n, options_), [this] {
                       combined_draco_->encode(cancel_check(), combined_preview_);
                       runner_->add(guarded({combined_draco_check()}));
                     }});
  } else {
    combined_drc_ = draco_not_written(n, draco_bytes(n, options_), budget_bytes_);
    warnings_.push_back("combined map: " +
                        combined_drc_.report["draco"]["reason"].get<std::string>());
  }
  if (options_.write_ply)
    tasks.push_back({"ply combined", kPlySecondsPerPoint * n, tile_bytes(), [this, &tiled] {
                       combined_ply_ = write_tiled_map_ply(tiled, combined_parts_, kCombinedMapName,
                                                           context_.work_dir, cancel_check());
                     }});
  if (options_.write_tiles)
    tasks.push_back({"tiles combined", kLodSecondsPerPoint * n, tile_bytes(), [this, &tiled] {
                       combined_tiles_ = write_map_tiles(tiled, combined_parts_, kCombinedMapName,
                                                         context_.work_dir, cancel_check());
                     }});
  tasks.push_back({"metrics inspection_combined", kMetricsSecondsPerPoint * n,
                   tile_bytes() * options_.threads, [this, &tiled] {
                     metrics_.combined = measure_tiled("inspection_combined", tiled,
                                                       combined_parts_, options_, cancel_check());
                   }});
  return tasks;
}

OutputTask OutputPlan::combined_draco_check() {
  const double n = static_cast<double>(combined_points_);
  return {"draco combined (check)", kDracoCheckSecondsPerPoint * n,
          (kGatheredBytesPerPoint + kDracoCheckBytesPerPoint) * n,
          [this] { combined_draco_->check(combined_drc_); }};
}

void OutputPlan::collect(const std::vector<std::string>& written, StageResult& out) {
  for (const auto& name : written) {
    MapOutput& map_output = drc_.at(name);
    merge_output(map_output, ply_.at(name));
    merge_output(map_output, tiles_.at(name));
    merge_output(map_output, preview_.at(name));
    out.report["sensors"][name]["map"] = map_output.report;
    out.artifacts.insert(out.artifacts.end(), map_output.artifacts.begin(),
                         map_output.artifacts.end());
  }
  merge_output(combined_drc_, combined_ply_);
  merge_output(combined_drc_, combined_tiles_);
  merge_output(combined_drc_, combined_preview_);
  if (!combined_drc_.report.contains("points")) combined_drc_.report["points"] = combined_points_;
  out.report["combined"] = combined_drc_.report;
  out.artifacts.insert(out.artifacts.end(), combined_drc_.artifacts.begin(),
                       combined_drc_.artifacts.end());
}

void OutputPlan::keep() {
  keep_ = true;
  task_log_.flush(context_.log);
}

}  // namespace keel::pipeline
