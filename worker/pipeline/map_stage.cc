// Stage `map`, as numbered steps:
//   1. options (--set map.x=v) and the scan sensors to map: every lidar and sonar unless
//      `sensors` names them; sensors on a servo tray (`mounted_on`) are skipped, because their
//      extrinsic varies with the tray angle and MapBuilder's TF tree holds static extrinsics;
//   2. poses (Sec. VI-C): keyframes from `trajectory_refined.tum` (an earlier `refine`) or
//      the recorded `map` poses, correcting the recorded `odometry` by Algorithm 2 so every
//      scan between keyframes has a pose; the TF tree W -> B -> S_i with the extrinsics of
//      MissionReader::extrinsic (mission.yaml, else the bag's /tf_static);
//   3. every scan of every sensor through a MapBuilder of its own (Fig. 5), `threads` scans at
//      a time and committed in order (MapBuilder::add_scans); the SLAM lidar's scans also
//      through SlamMapBuilder for the SLAM-map baseline;
//   4. per sensor: Draco (.drc) and PLY maps;
//   5. metrics of the SLAM map and the SLAM lidar's inspection map (Eqs. (23)-(26)), and the
//      combined map (Eq. (21)): its Draco and PLY files and metrics; Table V with the ratios.
//   Steps 4 and 5 are output tasks (OutputRunner): a sensor's start on one extra thread as soon
//   as its scans are in, while the next sensors scan; the rest, costliest first, on `threads`
//   threads once every map is built, as many side by side as a memory bound allows. The
//   combined map is encoded, written and measured from the sensor maps, never copied whole.
//   docs/map-filters.md explains the throughput and memory choices.
#include "worker/pipeline/map_stage.h"
#include "worker/pipeline/stage_options.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "proto/contract_error.h"
#include "worker/io/draco_codec.h"
#include "worker/io/mission_reader.h"
#include "worker/io/ply_cloud_writer.h"
#include "worker/io/tum.h"
#include "worker/mapping/map_metrics.h"
#include "worker/mapping/odometry_correction.h"
#include "worker/mapping/slam_map.h"
#include "worker/mapping/transform_tree.h"
#include "worker/mapping/voxel_accumulator.h"
#include "worker/pipeline/refine_stage.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::ContractError;
using proto::SensorType;

// Progress: scans take [0, kScansDone], the outputs and metrics the rest.
constexpr double kScansDone = 0.75;

void require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.map." + option + ": expected " + expected);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

json span_json(const Trajectory& poses) {
  if (poses.empty()) return {{"poses", 0}};
  return {{"poses", poses.size()},
          {"t_first_s", ns_to_seconds(poses.front().t_ns)},
          {"t_last_s", ns_to_seconds(poses.back().t_ns)},
          {"duration_s", ns_to_seconds(poses.back().t_ns - poses.front().t_ns)}};
}

// ---- step 1: sensors ----------------------------------------------------------------------

struct MappedSensor {
  std::string name;
  std::string type;  // "lidar" | "sonar"
  Pose3 T_body_sensor = Pose3::Identity();
};

struct SensorSelection {
  std::vector<MappedSensor> mapped;
  json skipped = json::array();  // [{sensor, reason}]
};

bool is_mappable_type(SensorType type) {
  return type == SensorType::kLidar || type == SensorType::kSonar;
}

SensorSelection select_sensors(const io::MissionReader& reader, const MapStageOptions& options) {
  const auto& manifest = reader.manifest();
  const bool explicit_list = !options.sensors.empty();
  std::vector<const proto::SensorSpec*> candidates;
  if (explicit_list) {
    for (const auto& name : options.sensors) {
      const proto::SensorSpec* spec = manifest.find_sensor(name);
      if (!spec) {
        std::vector<std::string> names;
        for (const auto& s : manifest.sensors) names.push_back(s.name);
        throw ContractError("options.map.sensors: mission has no sensor '" + name +
                            "' (it has: " + join_names(names) + ")");
      }
      if (!is_mappable_type(spec->type) || !spec->is_scans())
        throw ContractError("options.map.sensors: sensor '" + name + "' is a " +
                            proto::to_string(spec->type) +
                            ", expected a lidar or sonar with scans");
      candidates.push_back(spec);
    }
  } else {
    for (const auto& spec : manifest.sensors)
      if (is_mappable_type(spec.type) && spec.is_scans()) candidates.push_back(&spec);
  }
  SensorSelection selection;
  for (const proto::SensorSpec* spec : candidates) {
    if (!spec->mounted_on.empty()) {
      selection.skipped.push_back(
          {{"sensor", spec->name},
           {"reason", "rides the servo tray '" + spec->mounted_on +
                          "': its extrinsic varies with the tray angle, and the map's TF tree "
                          "holds static extrinsics only"}});
      continue;
    }
    const std::optional<Pose3> T_body_sensor = reader.extrinsic(spec->name);
    if (!T_body_sensor) {
      const std::string reason =
          "no T_body_sensor (neither in mission.yaml nor in the bag's /tf_static)";
      if (explicit_list) throw std::runtime_error("sensor '" + spec->name + "': " + reason);
      selection.skipped.push_back({{"sensor", spec->name}, {"reason", reason}});
      continue;
    }
    selection.mapped.push_back({spec->name, proto::to_string(spec->type), *T_body_sensor});
  }
  if (selection.mapped.empty())
    throw std::runtime_error(
        "map: no lidar or sonar scans to map (skipped: " + selection.skipped.dump() + ")");
  return selection;
}

// ---- step 2: poses ------------------------------------------------------------------------

struct Poses {
  Trajectory T_world_body;    // what the TF tree interpolates
  Trajectory slam_keyframes;  // the SLAM system's keyframes (recorded `map`), for the baseline
  json report = json::object();
};

Poses build_poses(const io::MissionReader& reader, const MapStageOptions& options,
                  const StageContext& context) {
  Poses poses;
  Trajectory keyframes;
  const fs::path refined_path = context.work_dir / kRefinedTrajectoryFile;
  std::error_code ec;
  if (fs::is_regular_file(refined_path, ec)) {
    keyframes = io::read_tum(refined_path);
    poses.report["keyframes"] = span_json(keyframes);
    poses.report["keyframes"]["source"] = kRefinedTrajectoryFile;
  } else if (reader.has_trajectory("map")) {
    keyframes = reader.read_trajectory("map");
    poses.report["keyframes"] = span_json(keyframes);
    poses.report["keyframes"]["source"] = "trajectories.map (recorded)";
  }
  if (reader.has_trajectory("map")) poses.slam_keyframes = reader.read_trajectory("map");

  const bool has_odometry = reader.has_trajectory("odometry");
  if (keyframes.empty()) {
    if (!has_odometry)
      throw std::runtime_error(
          "map needs poses: no trajectory_refined.tum from a refine stage, and mission.yaml has "
          "neither trajectories.map nor trajectories.odometry");
    poses.T_world_body = reader.read_trajectory("odometry");
    poses.report["keyframes"] = nullptr;
    poses.report["source"] = "trajectories.odometry as recorded (no keyframe poses to correct it)";
  } else if (has_odometry && options.odometry_correction) {
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
    throw std::runtime_error("map needs at least 2 poses to interpolate, found " +
                             std::to_string(poses.T_world_body.size()));
  poses.report["trajectory"] = span_json(poses.T_world_body);
  return poses;
}

// ---- step 4: outputs ----------------------------------------------------------------------

json filter_steps_json(const mapping::StageStats& stage) {
  json steps = json::array();
  for (const auto& step : stage.steps)
    steps.push_back(
        {{"filter", step.filter}, {"points_in", step.points_in}, {"points_out", step.points_out}});
  return {{"applications", stage.applications}, {"filters", steps}};
}

json stats_json(const mapping::SensorMapStats& s) {
  return {{"scans", s.scans},
          {"scans_outside_trajectory", s.scans_outside_trajectory},
          {"points_in", s.points_in},
          {"non_finite_points", s.non_finite_points},
          {"intermediary_maps", s.intermediary_maps},
          {"scan_stage", filter_steps_json(s.scan_stage)},
          {"intermediary_stage", filter_steps_json(s.intermediary_stage)},
          {"final_stage", filter_steps_json(s.final_stage)},
          {"points_out", s.points_out}};
}

// The filter that removed every remaining point (a DROR whose alpha_deg does not match the
// sensor's angular resolution, typically), or "" when the map kept points.
std::string emptied_by(const mapping::SensorMapStats& s) {
  const std::pair<const char*, const mapping::StageStats*> stages[] = {
      {"scan", &s.scan_stage}, {"intermediary", &s.intermediary_stage}, {"final", &s.final_stage}};
  for (const auto& [stage, stats] : stages)
    for (const auto& step : stats->steps)
      if (step.points_in > 0 && step.points_out == 0)
        return std::string(stage) + "-stage filter '" + step.filter + "' removed all " +
               std::to_string(step.points_in) +
               " points (check its parameters against the sensor, e.g. DROR's alpha_deg)";
  return "";
}

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// Start (seconds after the scans began), wall and CPU seconds of each output task, for the job
// log (CPU of the task's own thread: the metrics' helper threads are not counted).
class TaskLog {
 public:
  explicit TaskLog(std::chrono::steady_clock::time_point origin) : origin_(origin) {}
  void run(const std::string& name, const std::function<void()>& task) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_seconds();
    task();
    char line[256];
    std::snprintf(line, sizeof(line),
                  "map: output task %-28s start %6.2f s, %6.2f s wall, %6.2f s cpu", name.c_str(),
                  std::chrono::duration<double>(start - origin_).count(), seconds_since(start),
                  thread_cpu_seconds() - cpu_start);
    std::lock_guard<std::mutex> lock(mutex_);
    lines_.push_back(line);
  }
  void flush(const std::function<void(const std::string&)>& log) {
    for (const auto& line : lines_) log(line);
    lines_.clear();
  }

 private:
  std::chrono::steady_clock::time_point origin_;
  std::mutex mutex_;
  std::vector<std::string> lines_;
};

// One task of the outputs phase: `cost` (estimated CPU seconds) orders the tasks longest first,
// `bytes` (estimated peak allocation while it runs) bounds which may run side by side.
struct OutputTask {
  std::string name;
  double cost = 0.0;
  double bytes = 0.0;
  std::function<void()> run;
};

// Estimates per map point, measured on the keel-sim bridge (14.4 M points in the combined map):
// Draco encode and round trip ~0.34 us and, at its peak, ~48 bytes (Draco's copy of the input,
// its quantized attributes and the kd-tree's copy of them, the output); the metrics (20000
// query points) ~0.15 us and ~29 bytes (the cell grid); a PLY ~0.05 us (mostly the kernel's
// copy) and a buffer of fixed size.
constexpr double kDracoSecondsPerPoint = 0.34e-6;
constexpr double kDracoBytesPerPoint = 48.0;
// The two steps of a Draco file on their own: the encoding (same peak), and the round trip
// (~0.1 us; the decoder's quantized and float copies, ~32 bytes, and the file's ~3.6).
constexpr double kDracoEncodeSecondsPerPoint = 0.24e-6;
constexpr double kDracoCheckSecondsPerPoint = 0.10e-6;
constexpr double kDracoCheckBytesPerPoint = 35.0;
constexpr double kMetricsSecondsPerPoint = 0.15e-6;
constexpr double kMetricsBytesPerPoint = 29.0;
constexpr double kPlySecondsPerPoint = 0.05e-6;

OutputTask draco_task(const std::string& map, size_t points, std::function<void()> run) {
  return {"draco " + map, kDracoSecondsPerPoint * points, kDracoBytesPerPoint * points,
          std::move(run)};
}
OutputTask ply_task(const std::string& map, size_t points, std::function<void()> run) {
  return {"ply " + map, kPlySecondsPerPoint * points, 0.0, std::move(run)};
}
// `extra_bytes`: what the task allocates besides the cell grid.
OutputTask metrics_task(const std::string& map, size_t points, size_t extra_bytes,
                        std::function<void()> run) {
  return {"metrics " + map, kMetricsSecondsPerPoint * points,
          kMetricsBytesPerPoint * points + static_cast<double>(extra_bytes), std::move(run)};
}

// Runs output tasks, each once, on worker threads. A free worker starts the costliest task not
// started whose bytes fit beside those of the running tasks within the memory budget (any task
// runs when it would run alone), so the cores stay busy to the end (the longest task first)
// without raising the memory peak. Tasks may be added while workers run, also by a task: a
// sensor's outputs start on one worker while the next sensors scan, the rest once every map is
// built, and the combined map's Draco encoding adds its round trip.
class OutputRunner {
 public:
  explicit OutputRunner(TaskLog& log) : log_(log) {}
  // Stops before any task not started (after an exception elsewhere) and joins the workers.
  ~OutputRunner() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    changed_.notify_all();
    for (auto& worker : workers_) worker.join();
  }
  OutputRunner(const OutputRunner&) = delete;
  OutputRunner& operator=(const OutputRunner&) = delete;

  void add(std::vector<OutputTask> tasks) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto& task : tasks) {
        total_cost_ += task.cost;
        tasks_.push_back(std::move(task));
        started_.push_back(false);
        ++unstarted_;
      }
    }
    changed_.notify_all();
  }
  // At least `threads` workers from now on, with this memory budget (bytes).
  void run_with(int threads, double memory_budget) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      memory_budget_ = memory_budget;
    }
    changed_.notify_all();
    while (workers_.size() < static_cast<size_t>(std::max(threads, 1)))
      workers_.emplace_back([this] { work(); });
  }
  // No more tasks: waits for every task to run, reporting `done(fraction of the cost)` after
  // each from now on (serialized), and rethrows the first exception of a task.
  void finish(std::function<void(double)> done) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = std::move(done);
      closed_ = true;
    }
    changed_.notify_all();
    for (auto& worker : workers_) worker.join();
    workers_.clear();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  static constexpr size_t kNone = static_cast<size_t>(-1);

  size_t fitting() const {
    size_t best = kNone;
    for (size_t i = 0; i < tasks_.size(); ++i) {
      if (started_[i]) continue;
      if (running_ > 0 && running_bytes_ + tasks_[i].bytes > memory_budget_) continue;
      if (best == kNone || tasks_[i].cost > tasks_[best].cost) best = i;
    }
    return best;
  }

  void work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      size_t i = kNone;
      changed_.wait(lock, [&] {
        // A running task may still add tasks: no worker leaves before it ends.
        return error_ || stopping_ || (closed_ && unstarted_ == 0 && running_ == 0) ||
               (i = fitting()) != kNone;
      });
      if (error_ || stopping_ || i == kNone) return;
      started_[i] = true;
      --unstarted_;
      ++running_;
      running_bytes_ += tasks_[i].bytes;
      const std::string name = tasks_[i].name;
      const std::function<void()> run = tasks_[i].run;
      lock.unlock();
      std::exception_ptr failure;
      try {
        log_.run(name, run);
      } catch (...) {
        failure = std::current_exception();
      }
      lock.lock();
      --running_;
      running_bytes_ -= tasks_[i].bytes;
      if (failure && !error_) error_ = failure;
      cost_done_ += tasks_[i].cost;
      if (!failure && closed_ && done_ && total_cost_ > 0.0) done_(cost_done_ / total_cost_);
      changed_.notify_all();
    }
  }

  TaskLog& log_;
  std::mutex mutex_;
  std::condition_variable changed_;  // tasks added, a task finished, closed or stopping
  std::deque<OutputTask> tasks_;
  std::vector<bool> started_;
  size_t unstarted_ = 0, running_ = 0;
  double running_bytes_ = 0.0, memory_budget_ = 0.0, total_cost_ = 0.0, cost_done_ = 0.0;
  bool closed_ = false, stopping_ = false;
  std::exception_ptr error_;
  std::function<void(double)> done_;
  std::vector<std::thread> workers_;
};

// One map's artifacts and their figures for the report.
struct MapOutput {
  json report = json::object();
  std::vector<std::string> artifacts;
};

io::DracoOptions draco_options(const MapStageOptions& options) {
  io::DracoOptions draco;
  draco.position_bits = options.draco_position_bits;
  draco.compression_level = options.draco_compression_level;
  return draco;
}

// Writes map_<name>.drc of a map of `points` points, whose encoding took `earlier_seconds`
// and then ran from `start`; report {"points", "draco": {...}}.
MapOutput write_map_draco(const io::DracoEncoded& encoded, size_t points,
                          std::chrono::steady_clock::time_point start, double earlier_seconds,
                          const std::string& name, const MapStageOptions& options,
                          const fs::path& work_dir) {
  io::write_draco_file(work_dir / map_draco_file(name), encoded.bytes);
  MapOutput out;
  out.artifacts.push_back(map_draco_file(name));
  out.report = {{"points", points},
                {"draco",
                 {{"file", map_draco_file(name)},
                  {"bytes", encoded.bytes.size()},
                  {"bytes_per_point", static_cast<double>(encoded.bytes.size()) / points},
                  {"position_bits", options.draco_position_bits},
                  {"compression_level", options.draco_compression_level},
                  {"position_range_m", encoded.position_range_m},
                  {"max_position_error_m", encoded.max_position_error_m},
                  {"position_error_bound_m", encoded.position_error_bound_m},
                  {"error_method", encoded.error_method},
                  {"encode_seconds", earlier_seconds + seconds_since(start)}}}};
  return out;
}

// Writes map_<name>.ply (a map, or a combined map as its parts); report {"ply": {...}}.
template <typename Map>
MapOutput write_map_ply(const Map& map, const std::string& name, const fs::path& work_dir) {
  MapOutput out;
  io::write_ply_cloud(work_dir / map_ply_file(name), map);
  out.artifacts.push_back(map_ply_file(name));
  out.report["ply"] = {{"file", map_ply_file(name)},
                       {"bytes", fs::file_size(work_dir / map_ply_file(name))}};
  return out;
}

void merge_output(MapOutput& into, const MapOutput& part) {
  into.report.update(part.report);
  into.artifacts.insert(into.artifacts.end(), part.artifacts.begin(), part.artifacts.end());
}

// ---- step 5: metrics ----------------------------------------------------------------------

struct MetricsColumn {
  std::string name;
  mapping::MapMetrics metrics;
  double seconds = 0.0;
};

MetricsColumn measure(const std::string& name, const PointCloud& map,
                      const MapStageOptions& options) {
  mapping::MapMetricsOptions metrics_options;
  metrics_options.radius_m = options.metrics_radius_m;
  // All threads, although the metrics run as an output task beside others: the last tasks
  // then still use every core (the figures do not depend on the thread count).
  metrics_options.threads = options.threads;
  metrics_options.max_query_points = options.metrics_max_points;
  const auto start = std::chrono::steady_clock::now();
  MetricsColumn column{name, mapping::compute_map_metrics(map, metrics_options), 0.0};
  column.seconds = seconds_since(start);
  return column;
}

// Table V of seed 000: the mean of each metric per map, the SLAM map first, and how the
// inspection map (`primary`) changes it: density as a factor, roughness and planarity in %.
json table_v(const std::vector<MetricsColumn>& columns, const std::string& primary) {
  auto mean_of = [](const mapping::MapMetrics& m, const std::string& metric) {
    if (metric == "surface_density") return m.surface_density.mean;
    if (metric == "roughness") return m.roughness.mean;
    return m.planarity.mean;
  };
  json rows = json::array();
  const char* units[] = {"points/m^2", "m", "1"};
  const char* metrics[] = {"surface_density", "roughness", "planarity"};
  for (int k = 0; k < 3; ++k) {
    json row = {{"metric", metrics[k]}, {"unit", units[k]}};
    for (const auto& c : columns) row[c.name] = mean_of(c.metrics, metrics[k]);
    rows.push_back(row);
  }
  json out = {{"columns", json::array()}, {"rows", rows}, {"inspection_map", primary}};
  for (const auto& c : columns) out["columns"].push_back(c.name);
  const MetricsColumn* slam = nullptr;
  const MetricsColumn* inspection = nullptr;
  for (const auto& c : columns) {
    if (c.name == "slam_map") slam = &c;
    if (c.name == primary) inspection = &c;
  }
  if (!slam || !inspection) return out;
  const auto& s = slam->metrics;
  const auto& i = inspection->metrics;
  auto ratio = [](double a, double b) { return b != 0.0 ? json(a / b) : json(nullptr); };
  auto percent = [](double a, double b) {
    return b != 0.0 ? json(100.0 * (a / b - 1.0)) : json(nullptr);
  };
  out["ratios"] = {{"density_factor", ratio(i.surface_density.mean, s.surface_density.mean)},
                   {"roughness_change_percent", percent(i.roughness.mean, s.roughness.mean)},
                   {"planarity_change_percent", percent(i.planarity.mean, s.planarity.mean)},
                   {"paper_table_v",
                    {{"density_factor", 31986.9 / 337.124},
                     {"roughness_change_percent", 100.0 * (2.576e-2 / 3.637e-2 - 1.0)},
                     {"planarity_change_percent", 100.0 * (6.546e-1 / 4.686e-1 - 1.0)}}}};
  out["inspection_beats_slam"] = {
      {"surface_density", i.surface_density.mean > s.surface_density.mean},
      {"roughness", i.roughness.mean < s.roughness.mean},
      {"planarity", i.planarity.mean > s.planarity.mean}};
  return out;
}

// ---- the stage ----------------------------------------------------------------------------

class MapStage : public Stage {
 public:
  std::string name() const override { return "map"; }

  StageResult run(StageContext& context) override {
    const auto stage_start = std::chrono::steady_clock::now();
    // Step 1: options, mission, sensors.
    const MapStageOptions options = MapStageOptions::from_json(context.options);
    io::MissionReader reader(io::load_mission(context.mission_dir));
    const SensorSelection selection = select_sensors(reader, options);
    for (const auto& item : options.sensor_filters.items()) {
      const bool mapped = std::any_of(selection.mapped.begin(), selection.mapped.end(),
                                      [&](const MappedSensor& s) { return s.name == item.key(); });
      if (!mapped) {
        std::vector<std::string> names;
        for (const auto& s : selection.mapped) names.push_back(s.name);
        throw ContractError("options.map.sensor_filters." + item.key() +
                            ": no such sensor is mapped (mapped: " + join_names(names) + ")");
      }
    }
    context.check_canceled();

    // Step 2: poses and the TF tree.
    const Poses poses = build_poses(reader, options, context);
    mapping::TransformTree tree(poses.T_world_body, "map poses");
    mapping::MapBuilderOptions builder_options;
    builder_options.scans_per_intermediary = options.scans_per_intermediary;
    builder_options.final_voxel_merge_radius_leaves = options.final_voxel_merge_radius_leaves;
    builder_options.deskew.max_sweep_duration_s = options.max_sweep_duration_s;
    builder_options.threads = options.threads;
    for (const auto& s : selection.mapped) {
      tree.set_extrinsic(s.name, s.T_body_sensor);
      builder_options.sensors[s.name] = options.sensor_options(s.name, s.type);
    }
    // One MapBuilder per sensor (a sensor's map depends on its own scans only, Fig. 5): a
    // sensor's outputs start once its last scan is in, while the next sensors scan.
    std::map<std::string, std::unique_ptr<mapping::MapBuilder>> builders;
    for (const auto& s : selection.mapped) {
      if (builders.count(s.name)) continue;
      mapping::MapBuilderOptions one = builder_options;
      one.sensors = {{s.name, builder_options.sensors.at(s.name)}};
      builders.emplace(s.name, std::make_unique<mapping::MapBuilder>(tree, std::move(one)));
    }

    // The SLAM-map baseline: the SLAM lidar's scans at the SLAM system's keyframes.
    const MappedSensor* slam_sensor = nullptr;
    for (const auto& s : selection.mapped)
      if (options.slam_sensor.empty() ? s.type == "lidar" : s.name == options.slam_sensor) {
        slam_sensor = &s;
        break;
      }
    if (!options.slam_sensor.empty() && !slam_sensor)
      throw ContractError("options.map.slam_sensor: '" + options.slam_sensor +
                          "' is not among the mapped sensors");
    std::optional<mapping::SlamMapBuilder> slam;
    if (slam_sensor) {
      mapping::SlamMapOptions slam_options;
      slam_options.keyframe_leaf_m = options.slam_keyframe_leaf_m;
      slam.emplace(poses.slam_keyframes, slam_sensor->T_body_sensor, slam_options, &tree,
                   slam_sensor->name);
    }

    // Step 3: every scan, one at a time. Scan counts are known up front (index.csv / bag).
    std::vector<std::unique_ptr<io::ScanSource>> sources;
    size_t total_scans = 0;
    for (const auto& s : selection.mapped) {
      sources.push_back(reader.open_scans(s.name));
      total_scans += sources.back()->size();
    }
    context.log("map: " + std::to_string(total_scans) + " scans of " +
                std::to_string(selection.mapped.size()) + " sensors, " +
                std::to_string(poses.T_world_body.size()) + " poses");

    // Steps 4 and 5 run as output tasks (OutputRunner): per sensor, Draco and PLY files; the
    // metrics of the SLAM map and of the SLAM lidar's inspection map; then the combined map
    // (Eq. (21)), kept as its parts, the sensor maps in name order (MapBuilder's), never
    // copied whole. Results land in slots made before any task runs.
    const auto scans_start = std::chrono::steady_clock::now();
    TaskLog task_log(scans_start);
    std::map<std::string, MapOutput> drc, ply;
    for (const auto& s : selection.mapped) {
      drc[s.name];
      ply[s.name];
    }
    MapOutput combined_output, combined_ply;
    PointCloud slam_map;
    std::optional<MetricsColumn> slam_column, inspection, combined_column;
    auto sensor_map = [&](const std::string& name) -> const PointCloud& {
      return builders.at(name)->sensor_map(name);
    };
    auto guarded = [&context](std::vector<OutputTask> tasks) {
      for (auto& task : tasks)
        task.run = [&context, run = std::move(task.run)] {
          context.check_canceled();
          run();
        };
      return tasks;
    };
    // The tasks of a sensor whose map is built.
    auto sensor_tasks = [&](const std::string& name) {
      std::vector<OutputTask> tasks;
      const PointCloud& map = sensor_map(name);
      if (map.empty()) return tasks;
      tasks.push_back(draco_task(name, map.size(), [&, name, &map = map] {
        const auto start = std::chrono::steady_clock::now();
        drc.at(name) =
            write_map_draco(io::encode_draco_point_cloud(map, {}, draco_options(options)),
                            map.size(), start, 0.0, name, options, context.work_dir);
      }));
      if (options.write_ply)
        tasks.push_back(ply_task(name, map.size(), [&, name, &map = map] {
          ply.at(name) = write_map_ply(map, name, context.work_dir);
        }));
      if (slam && name == slam_sensor->name) {
        tasks.push_back(metrics_task("inspection_" + name, map.size(), 0, [&, name, &map = map] {
          inspection = measure("inspection_" + name, map, options);
        }));
      }
      return tasks;
    };
    auto slam_tasks = [&] {
      std::vector<OutputTask> tasks;
      if (!slam_map.empty())
        tasks.push_back(metrics_task("slam_map", slam_map.size(), 0, [&] {
          slam_column = measure("slam_map", slam_map, options);
        }));
      return tasks;
    };
    std::vector<const PointCloud*> combined_parts;
    size_t combined_points = 0;
    io::DracoEncoded combined_encoded;
    double combined_encode_seconds = 0.0;
    OutputTask combined_check;
    // Declared after everything its tasks use: on an exception it joins them first.
    OutputRunner runner(task_log);
    // Early outputs take one thread beside the scans' `threads` (none when threads = 1).
    const bool early_outputs = options.threads >= 2;
    if (early_outputs) runner.run_with(1, 0.0);
    std::vector<std::string> output_queued;  // sensors whose tasks were added
    bool slam_queued = false;

    size_t scans_done = 0;
    for (size_t k = 0; k < sources.size(); ++k) {
      const MappedSensor& sensor = selection.mapped[k];
      // MapBuilder pulls scans from this feed on options.threads threads (calls never overlap,
      // so the source, the SLAM baseline and progress see scans one at a time, in order).
      builders.at(sensor.name)->add_scans([&](std::string& sensor_name, PointCloud& scan) {
        context.check_canceled();
        if (!sources[k]->next(scan)) return false;
        sensor_name = sensor.name;
        if (slam && &sensor == slam_sensor) slam->add_scan(scan);
        ++scans_done;
        if (total_scans > 0)
          context.progress(kScansDone * static_cast<double>(scans_done) / total_scans);
        return true;
      });
      sources[k].reset();
      const bool last_of_sensor =
          std::none_of(selection.mapped.begin() + k + 1, selection.mapped.end(),
                       [&](const MappedSensor& s) { return s.name == sensor.name; });
      if (!last_of_sensor) continue;
      context.check_canceled();
      builders.at(sensor.name)->finish();
      if (slam && sensor.name == slam_sensor->name) slam_map = slam->finish();
      if (early_outputs && k + 1 < sources.size()) {
        if (!builders.at(sensor.name)->sensors().empty()) {
          runner.add(guarded(sensor_tasks(sensor.name)));
          output_queued.push_back(sensor.name);
        }
        if (slam && sensor.name == slam_sensor->name) {
          runner.add(guarded(slam_tasks()));
          slam_queued = true;
        }
      }
    }
    context.check_canceled();
    const double scans_seconds = seconds_since(scans_start);
    std::vector<std::string> built;  // sensors that had scans, in name order
    for (const auto& [name, builder] : builders)
      if (!builder->sensors().empty()) built.push_back(name);
    size_t points_in = 0;
    for (const auto& name : built) points_in += builders.at(name)->stats(name).points_in;
    context.log("map: " + std::to_string(points_in) + " points in " +
                std::to_string(scans_seconds) + " s");

    // Step 4: per-sensor and combined maps.
    StageResult out;
    json& r = out.report;
    r["options"] = options.to_json();
    r["poses"] = poses.report;
    r["skipped_sensors"] = selection.skipped;
    json warnings = json::array();
    json sensors = json::object();
    const auto outputs_start = std::chrono::steady_clock::now();
    const double outputs_cpu_start = process_cpu_seconds();
    std::vector<std::string> written;  // sensors with a non-empty map, largest first
    for (const auto& s : selection.mapped) {
      json entry = {{"type", s.type},
                    {"filters", mapping::to_json(builder_options.sensors.at(s.name))}};
      if (std::find(built.begin(), built.end(), s.name) == built.end()) {
        entry["stats"] = nullptr;
        warnings.push_back("sensor '" + s.name + "': no scans");
        sensors[s.name] = entry;
        continue;
      }
      const mapping::SensorMapStats& stats = builders.at(s.name)->stats(s.name);
      entry["stats"] = stats_json(stats);
      if (sensor_map(s.name).empty()) {
        warnings.push_back("sensor '" + s.name + "': the map is empty (every point filtered, or " +
                           "every scan outside the trajectory); no artifacts written");
      } else if (std::find(written.begin(), written.end(), s.name) == written.end()) {
        written.push_back(s.name);
      }
      if (stats.scans_outside_trajectory > 0)
        warnings.push_back("sensor '" + s.name +
                           "': " + std::to_string(stats.scans_outside_trajectory) +
                           " scans outside the trajectory were skipped");
      if (const std::string w = emptied_by(stats); !w.empty())
        warnings.push_back("sensor '" + s.name + "': " + w);
      sensors[s.name] = entry;
    }
    std::stable_sort(written.begin(), written.end(),
                     [&](const std::string& a, const std::string& b) {
                       return sensor_map(a).size() > sensor_map(b).size();
                     });
    r["sensors"] = sensors;
    std::string primary = "inspection_combined";  // Table V's inspection map
    if (slam) {
      r["slam_map"] = {{"sensor", slam_sensor->name},
                       {"keyframes", slam->keyframes()},
                       {"keyframes_used", slam->keyframes_used()},
                       {"keyframe_leaf_m", options.slam_keyframe_leaf_m},
                       {"points", slam_map.size()}};
      if (slam_map.empty())
        warnings.push_back("SLAM map: no scan of '" + slam_sensor->name +
                           "' matches a keyframe; no baseline");
    } else {
      r["slam_map"] = nullptr;
      warnings.push_back("no lidar mapped: no SLAM-map baseline");
    }
    for (const auto& name : built) {
      const PointCloud& map = sensor_map(name);
      if (map.empty()) continue;
      combined_parts.push_back(&map);
      combined_points += map.size();
    }
    if (combined_points == 0) throw std::runtime_error("map: every map is empty; nothing to write");
    if (slam && std::find(written.begin(), written.end(), slam_sensor->name) != written.end())
      primary = "inspection_" + slam_sensor->name;

    std::vector<OutputTask> tasks;
    for (const auto& name : built) {
      if (std::find(output_queued.begin(), output_queued.end(), name) != output_queued.end())
        continue;
      for (auto& task : sensor_tasks(name)) tasks.push_back(std::move(task));
    }
    if (slam && !slam_queued)
      for (auto& task : slam_tasks()) tasks.push_back(std::move(task));
    // The combined map's Draco file, the longest task, in two: its round trip may then run
    // beside the combined metrics (the encoding's peak could not).
    const double n_combined = static_cast<double>(combined_points);
    combined_check = {
        "draco combined (check)", kDracoCheckSecondsPerPoint * n_combined,
        kDracoCheckBytesPerPoint * n_combined, [&] {
          const auto start = std::chrono::steady_clock::now();
          io::measure_draco_point_cloud(combined_parts, draco_options(options), &combined_encoded);
          combined_output =
              write_map_draco(combined_encoded, combined_points, start, combined_encode_seconds,
                              kCombinedMapName, options, context.work_dir);
          combined_encoded = io::DracoEncoded{};
        }};
    tasks.push_back({"draco combined (encode)", kDracoEncodeSecondsPerPoint * n_combined,
                     kDracoBytesPerPoint * n_combined, [&] {
                       const auto start = std::chrono::steady_clock::now();
                       combined_encoded = io::encode_draco_point_cloud_bytes(
                           combined_parts, draco_options(options));
                       combined_encode_seconds = seconds_since(start);
                       runner.add(guarded({std::move(combined_check)}));
                     }});
    if (options.write_ply)
      tasks.push_back(ply_task(kCombinedMapName, combined_points, [&] {
        combined_ply = write_map_ply(combined_parts, kCombinedMapName, context.work_dir);
      }));
    // The metrics read positions only: the combined positions are gathered for them alone.
    tasks.push_back(metrics_task(
        "inspection_combined", combined_points, sizeof(Eigen::Vector3f) * combined_points, [&] {
          PointCloud positions;
          positions.xyz.reserve(combined_points);
          for (const PointCloud* part : combined_parts)
            positions.xyz.insert(positions.xyz.end(), part->xyz.begin(), part->xyz.end());
          combined_column = measure("inspection_combined", positions, options);
        }));
    runner.add(guarded(std::move(tasks)));
    // Memory: the combined map's Draco encode and metrics together, the peak of the outputs
    // when they ran once the sensor maps were merged, bounds the tasks running at once.
    runner.run_with(options.threads, (kDracoBytesPerPoint + kMetricsBytesPerPoint) *
                                         static_cast<double>(combined_points));
    runner.finish([&](double f) { context.progress(kScansDone + (1.0 - kScansDone) * f); });
    context.check_canceled();

    for (const auto& name : written) {
      MapOutput& map_output = drc.at(name);
      merge_output(map_output, ply.at(name));
      r["sensors"][name]["map"] = map_output.report;
      out.artifacts.insert(out.artifacts.end(), map_output.artifacts.begin(),
                           map_output.artifacts.end());
    }
    merge_output(combined_output, combined_ply);
    r["combined"] = combined_output.report;
    out.artifacts.insert(out.artifacts.end(), combined_output.artifacts.begin(),
                         combined_output.artifacts.end());
    std::vector<MetricsColumn> columns;
    for (auto* column : {&slam_column, &inspection, &combined_column})
      if (*column) columns.push_back(std::move(**column));
    json metrics = {{"radius_m", options.metrics_radius_m},
                    {"max_query_points", options.metrics_max_points},
                    {"maps", json::object()}};
    double metrics_seconds = 0.0;
    size_t metrics_queries = 0;
    for (const auto& c : columns) {
      metrics["maps"][c.name] = mapping::to_json(c.metrics);
      metrics["maps"][c.name]["seconds"] = c.seconds;
      metrics_seconds += c.seconds;
      metrics_queries += c.metrics.query_points;
    }
    metrics["table_v"] = table_v(columns, primary);
    r["metrics"] = metrics;
    const double stage_seconds = seconds_since(stage_start);
    r["timing"] = {
        {"stage_seconds", stage_seconds},
        {"stage_input_points_per_second", stage_seconds > 0 ? points_in / stage_seconds : 0.0},
        {"outputs_and_metrics_seconds", seconds_since(outputs_start)},
        {"threads", options.threads},
        {"scans_seconds", scans_seconds},
        {"input_points", points_in},
        {"input_points_per_second", scans_seconds > 0 ? points_in / scans_seconds : 0.0},
        {"metrics_seconds", metrics_seconds},
        {"metrics_query_points_per_second",
         metrics_seconds > 0 ? metrics_queries / metrics_seconds : 0.0}};
    r["warnings"] = warnings;
    task_log.flush(context.log);
    context.log("map: outputs and metrics " + std::to_string(seconds_since(outputs_start)) +
                " s wall, " + std::to_string(process_cpu_seconds() - outputs_cpu_start) + " s cpu");
    context.progress(1.0);
    return out;
  }
};

}  // namespace

std::string map_draco_file(const std::string& sensor) { return "map_" + sensor + ".drc"; }
std::string map_ply_file(const std::string& sensor) { return "map_" + sensor + ".ply"; }

MapStageOptions MapStageOptions::from_json(const json& options) {
  MapStageOptions o;
  if (options.is_null()) return o;
  StageOptionReader r(options, "map");
  if (r.has("sensors")) {
    // `--set map.sensors=lidar_h` arrives as a string; `["lidar_h","sonar"]` as an array.
    const json& value = r.at("sensors");
    o.sensors = value.is_string() ? std::vector<std::string>{value.get<std::string>()}
                                  : r.optional<std::vector<std::string>>("sensors", {});
  }
  o.lidar_filters = r.optional<json>("lidar_filters", o.lidar_filters);
  o.sonar_filters = r.optional<json>("sonar_filters", o.sonar_filters);
  o.sensor_filters = r.optional<json>("sensor_filters", o.sensor_filters);
  o.final_voxel_leaf_m = r.optional<double>("final_voxel_leaf_m", o.final_voxel_leaf_m);
  o.final_voxel_merge_radius_leaves =
      r.optional<double>("final_voxel_merge_radius_leaves", o.final_voxel_merge_radius_leaves);
  o.scans_per_intermediary = r.optional<int>("scans_per_intermediary", o.scans_per_intermediary);
  o.deskew = r.optional<bool>("deskew", o.deskew);
  o.max_sweep_duration_s = r.optional<double>("max_sweep_duration_s", o.max_sweep_duration_s);
  o.odometry_correction = r.optional<bool>("odometry_correction", o.odometry_correction);
  o.draco_position_bits = r.optional<int>("draco_position_bits", o.draco_position_bits);
  o.draco_compression_level = r.optional<int>("draco_compression_level", o.draco_compression_level);
  o.write_ply = r.optional<bool>("write_ply", o.write_ply);
  o.metrics_radius_m = r.optional<double>("metrics_radius_m", o.metrics_radius_m);
  const long long max_points =
      r.optional<long long>("metrics_max_points", static_cast<long long>(o.metrics_max_points));
  require(max_points >= 0, "metrics_max_points", "an integer >= 0 (0: every point)");
  o.metrics_max_points = static_cast<size_t>(max_points);
  o.slam_sensor = r.optional<std::string>("slam_sensor", o.slam_sensor);
  o.slam_keyframe_leaf_m = r.optional<double>("slam_keyframe_leaf_m", o.slam_keyframe_leaf_m);
  o.threads = r.optional<int>("threads", o.threads);
  r.finish();

  require(o.lidar_filters.is_object(), "lidar_filters",
          "an object {scan_filters, intermediary_filters, final_filters, deskew}");
  require(o.sonar_filters.is_object(), "sonar_filters",
          "an object {scan_filters, intermediary_filters, final_filters, deskew}");
  require(o.sensor_filters.is_object(), "sensor_filters",
          "an object {\"<sensor>\": {scan_filters, intermediary_filters, final_filters, deskew}}");
  require(std::isfinite(o.final_voxel_leaf_m) && o.final_voxel_leaf_m >= 0.0, "final_voxel_leaf_m",
          "a leaf in metres >= 0 (0: no final voxel grid)");
  require(o.final_voxel_merge_radius_leaves >= 0.0 &&
              o.final_voxel_merge_radius_leaves <= mapping::VoxelAccumulator::kMaxMergeLeaves,
          "final_voxel_merge_radius_leaves", "a radius in leaves in [0, 2] (0: no merging)");
  require(o.scans_per_intermediary >= 1 && o.scans_per_intermediary <= 100000,
          "scans_per_intermediary", "an integer in [1, 100000]");
  require(o.max_sweep_duration_s > 0.0, "max_sweep_duration_s", "> 0");
  require(o.draco_position_bits >= 1 && o.draco_position_bits <= 30, "draco_position_bits",
          "an integer in [1, 30]");
  require(o.draco_compression_level >= 0 && o.draco_compression_level <= 10,
          "draco_compression_level", "an integer in [0, 10]");
  require(std::isfinite(o.metrics_radius_m) && o.metrics_radius_m > 0.0, "metrics_radius_m",
          "a radius in metres > 0");
  require(std::isfinite(o.slam_keyframe_leaf_m) && o.slam_keyframe_leaf_m > 0.0,
          "slam_keyframe_leaf_m", "a leaf in metres > 0");
  require(o.threads >= 1 && o.threads <= 256, "threads", "an integer in [1, 256]");
  // The filter chains fail here, naming the option path, rather than halfway through a job.
  try {
    o.sensor_options("", "lidar");
    o.sensor_options("", "sonar");
    for (const auto& item : o.sensor_filters.items()) {
      o.sensor_options(item.key(), "lidar");
      o.sensor_options(item.key(), "sonar");
    }
  } catch (const std::invalid_argument& e) {
    throw ContractError(e.what());
  }
  return o;
}

mapping::SensorMapOptions MapStageOptions::sensor_options(const std::string& sensor,
                                                          const std::string& type) const {
  mapping::SensorMapOptions defaults;
  defaults.scan_filters = type == "sonar" ? mapping::table_iv_sonar_scan_filters()
                                          : mapping::table_iv_lidar_scan_filters();
  if (final_voxel_leaf_m > 0.0)
    defaults.final_filters.filters.push_back(mapping::VoxelGridFilter{final_voxel_leaf_m});
  defaults.deskew = deskew;
  const bool sonar = type == "sonar";
  defaults = mapping::sensor_map_options_from_json(
      sonar ? sonar_filters : lidar_filters,
      sonar ? "options.map.sonar_filters" : "options.map.lidar_filters", defaults);
  if (!sensor.empty() && sensor_filters.contains(sensor))
    defaults = mapping::sensor_map_options_from_json(
        sensor_filters.at(sensor), "options.map.sensor_filters." + sensor, defaults);
  return defaults;
}

json MapStageOptions::to_json() const {
  return {{"sensors", sensors},
          {"lidar_filters", lidar_filters},
          {"sonar_filters", sonar_filters},
          {"sensor_filters", sensor_filters},
          {"final_voxel_leaf_m", final_voxel_leaf_m},
          {"final_voxel_merge_radius_leaves", final_voxel_merge_radius_leaves},
          {"scans_per_intermediary", scans_per_intermediary},
          {"deskew", deskew},
          {"max_sweep_duration_s", max_sweep_duration_s},
          {"odometry_correction", odometry_correction},
          {"draco_position_bits", draco_position_bits},
          {"draco_compression_level", draco_compression_level},
          {"write_ply", write_ply},
          {"metrics_radius_m", metrics_radius_m},
          {"metrics_max_points", metrics_max_points},
          {"slam_sensor", slam_sensor},
          {"slam_keyframe_leaf_m", slam_keyframe_leaf_m},
          {"threads", threads}};
}

std::unique_ptr<Stage> make_map_stage() { return std::make_unique<MapStage>(); }

}  // namespace keel::pipeline
