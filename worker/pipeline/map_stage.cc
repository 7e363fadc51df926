// Stage `map`, as numbered steps:
//   1. options (--set map.x=v) and the scan sensors to map: every lidar and sonar unless
//      `sensors` names them; sensors on a servo tray (`mounted_on`) are skipped, because their
//      extrinsic varies with the tray angle and MapBuilder's TF tree holds static extrinsics;
//   2. poses (Sec. VI-C): keyframes from `trajectory_refined.tum` (an earlier `refine`) or
//      the recorded `map` poses, correcting the recorded `odometry` by Algorithm 2 so every
//      scan between keyframes has a pose; the TF tree W -> B -> S_i with the extrinsics of
//      MissionReader::extrinsic (mission.yaml, else the bag's /tf_static);
//   3. every scan of every sensor through MapBuilder (Fig. 5), `threads` scans at a time and
//      committed in order (MapBuilder::add_scans); the SLAM lidar's scans also through
//      SlamMapBuilder for the SLAM-map baseline;
//   4. per sensor: Draco (.drc) and PLY maps, written side by side;
//   5. metrics of the SLAM map and the SLAM lidar's inspection map (Eqs. (23)-(26)), then the
//      combined map (Eq. (21)): its Draco file beside its PLY file and metrics; Table V with
//      the ratios. docs/map-filters.md explains the throughput and memory choices.
#include "worker/pipeline/map_stage.h"
#include "worker/pipeline/stage_options.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
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

// Progress: scans take [0, kScansDone], outputs up to kOutputsDone, metrics the rest.
constexpr double kScansDone = 0.75;
constexpr double kOutputsDone = 0.85;

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

// Runs the tasks on up to `threads` threads, each task once, in order of submission; the first
// exception is rethrown after every started task has finished (the others are not started).
void run_tasks(const std::vector<std::function<void()>>& tasks, int threads) {
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (size_t i = next++; i < tasks.size() && !failed; i = next++) {
      try {
        tasks[i]();
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> workers;
  const size_t count = std::min<size_t>(std::max(threads, 1), tasks.size());
  for (size_t w = 1; w < count; ++w) workers.emplace_back(work);
  work();
  for (auto& worker : workers) worker.join();
  if (error) std::rethrow_exception(error);
}

// One map's artifacts and their figures for the report.
struct MapOutput {
  json report = json::object();
  std::vector<std::string> artifacts;
};

// Writes map_<name>.drc; report {"points", "draco": {...}}.
MapOutput write_map_draco(const PointCloud& map, const std::string& name,
                          const MapStageOptions& options, const fs::path& work_dir) {
  io::DracoOptions draco;
  draco.position_bits = options.draco_position_bits;
  draco.compression_level = options.draco_compression_level;
  const auto start = std::chrono::steady_clock::now();
  io::DracoEncoded encoded = io::encode_draco_point_cloud(map, {}, draco);
  io::write_draco_file(work_dir / map_draco_file(name), encoded.bytes);
  MapOutput out;
  out.artifacts.push_back(map_draco_file(name));
  out.report = {{"points", map.size()},
                {"draco",
                 {{"file", map_draco_file(name)},
                  {"bytes", encoded.bytes.size()},
                  {"bytes_per_point", static_cast<double>(encoded.bytes.size()) / map.size()},
                  {"position_bits", draco.position_bits},
                  {"compression_level", draco.compression_level},
                  {"position_range_m", encoded.position_range_m},
                  {"max_position_error_m", encoded.max_position_error_m},
                  {"position_error_bound_m", encoded.position_error_bound_m},
                  {"error_method", encoded.error_method},
                  {"encode_seconds", seconds_since(start)}}}};
  return out;
}

// Writes map_<name>.ply when options.write_ply; report {"ply": {...}} or nothing.
MapOutput write_map_ply(const PointCloud& map, const std::string& name,
                        const MapStageOptions& options, const fs::path& work_dir) {
  MapOutput out;
  if (!options.write_ply) return out;
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
    mapping::MapBuilder builder(tree, builder_options);

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
    const auto scans_start = std::chrono::steady_clock::now();
    size_t scans_done = 0, source = 0;
    // MapBuilder pulls scans from this feed on options.threads threads (calls never overlap,
    // so the sources, the SLAM baseline and progress see scans one at a time, in order).
    builder.add_scans([&](std::string& sensor_name, PointCloud& scan) {
      while (source < sources.size()) {
        context.check_canceled();
        if (sources[source]->next(scan)) {
          const MappedSensor& sensor = selection.mapped[source];
          sensor_name = sensor.name;
          if (slam && &sensor == slam_sensor) slam->add_scan(scan);
          ++scans_done;
          if (total_scans > 0)
            context.progress(kScansDone * static_cast<double>(scans_done) / total_scans);
          return true;
        }
        sources[source++].reset();
      }
      return false;
    });
    context.check_canceled();
    builder.finish();
    const double scans_seconds = seconds_since(scans_start);
    const std::vector<std::string> built = builder.sensors();  // sensors that had scans
    size_t points_in = 0;
    for (const auto& name : built) points_in += builder.stats(name).points_in;
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
      entry["stats"] = stats_json(builder.stats(s.name));
      if (builder.sensor_map(s.name).empty()) {
        warnings.push_back("sensor '" + s.name + "': the map is empty (every point filtered, or " +
                           "every scan outside the trajectory); no artifacts written");
      } else {
        written.push_back(s.name);
      }
      if (builder.stats(s.name).scans_outside_trajectory > 0)
        warnings.push_back("sensor '" + s.name +
                           "': " + std::to_string(builder.stats(s.name).scans_outside_trajectory) +
                           " scans outside the trajectory were skipped");
      if (const std::string w = emptied_by(builder.stats(s.name)); !w.empty())
        warnings.push_back("sensor '" + s.name + "': " + w);
      sensors[s.name] = entry;
    }
    // Draco encoding is single-threaded: the maps are written side by side, largest first.
    std::sort(written.begin(), written.end(), [&](const std::string& a, const std::string& b) {
      return builder.sensor_map(a).size() > builder.sensor_map(b).size();
    });
    std::vector<MapOutput> drc(written.size()), ply(written.size());
    std::vector<std::function<void()>> write_tasks;
    for (size_t i = 0; i < written.size(); ++i)
      write_tasks.push_back([&, i] {
        context.check_canceled();
        drc[i] =
            write_map_draco(builder.sensor_map(written[i]), written[i], options, context.work_dir);
      });
    for (size_t i = 0; i < written.size(); ++i)
      write_tasks.push_back([&, i] {
        ply[i] =
            write_map_ply(builder.sensor_map(written[i]), written[i], options, context.work_dir);
      });
    run_tasks(write_tasks, options.threads);
    for (size_t i = 0; i < written.size(); ++i) {
      merge_output(drc[i], ply[i]);
      sensors[written[i]]["map"] = drc[i].report;
      out.artifacts.insert(out.artifacts.end(), drc[i].artifacts.begin(), drc[i].artifacts.end());
    }
    r["sensors"] = sensors;
    context.progress(kOutputsDone);
    context.check_canceled();

    // Step 5: Table V (the SLAM map and the SLAM lidar's inspection map), then the combined
    // map (Eq. (21)): built once the sensor maps are written, which it replaces in memory,
    // written (Draco and PLY side by side) and measured.
    std::vector<MetricsColumn> columns;
    std::string primary = "inspection_combined";
    if (slam) {
      const PointCloud slam_map = slam->finish();
      r["slam_map"] = {{"sensor", slam_sensor->name},
                       {"keyframes", slam->keyframes()},
                       {"keyframes_used", slam->keyframes_used()},
                       {"keyframe_leaf_m", options.slam_keyframe_leaf_m},
                       {"points", slam_map.size()}};
      if (!slam_map.empty()) {
        columns.push_back(measure("slam_map", slam_map, options));
      } else {
        warnings.push_back("SLAM map: no scan of '" + slam_sensor->name +
                           "' matches a keyframe; no baseline");
      }
      if (std::find(written.begin(), written.end(), slam_sensor->name) != written.end()) {
        primary = "inspection_" + slam_sensor->name;
        columns.push_back(measure(primary, builder.sensor_map(slam_sensor->name), options));
      }
      context.check_canceled();
    } else {
      r["slam_map"] = nullptr;
      warnings.push_back("no lidar mapped: no SLAM-map baseline");
    }
    context.progress(kOutputsDone + 0.05);

    const PointCloud combined = builder.take_combined_map();
    if (combined.empty()) throw std::runtime_error("map: every map is empty; nothing to write");
    MapOutput combined_output, combined_ply;
    MetricsColumn combined_metrics;
    run_tasks(
        {[&] {
           combined_output = write_map_draco(combined, kCombinedMapName, options, context.work_dir);
         },
         [&] {
           combined_ply = write_map_ply(combined, kCombinedMapName, options, context.work_dir);
           combined_metrics = measure("inspection_combined", combined, options);
         }},
        options.threads);
    merge_output(combined_output, combined_ply);
    r["combined"] = combined_output.report;
    out.artifacts.insert(out.artifacts.end(), combined_output.artifacts.begin(),
                         combined_output.artifacts.end());
    columns.push_back(std::move(combined_metrics));
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
