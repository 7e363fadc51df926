// Stage `map`, as numbered steps (MapRun's step functions below):
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
//   Steps 4 and 5 are output tasks (OutputRunner) that overlap the scans: a sensor's start on
//   one extra thread as soon as its last scan is in, while the next sensors scan; the rest run
//   costliest first on `threads` threads once every map is built, as many side by side as a
//   memory budget allows. The combined map is encoded, written and measured from the sensor
//   maps, never copied whole. docs/map-filters.md explains the throughput and memory choices.
#include "worker/stages/map/stage.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage_options.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>

#include "proto/contract_error.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mission_reader.h"
#include "worker/io/cloud/ply_cloud_writer.h"
#include "worker/io/tum.h"
#include "worker/mapping/map_metrics.h"
#include "worker/mapping/odometry_correction.h"
#include "worker/mapping/slam_map.h"
#include "worker/mapping/transform_tree.h"
#include "worker/mapping/voxel_accumulator.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/map/map_outputs.h"
#include "worker/stages/map/output_runner.h"
#include "worker/stages/refine/artifacts.h"
#include "worker/stages/map/tiled_maps.h"
#include "worker/stages/map/tiled_outputs.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::ContractError;
using proto::SensorType;

// Progress: scans take [0, kScansDone], the outputs and metrics the rest.
constexpr double kScansDone = 0.75;

void local_require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.map." + option + ": expected " + expected);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The stage's peak RSS: the kernel's high-water mark, reset when the stage starts (writing 5
// to /proc/self/clear_refs), so an earlier stage of the same process does not count.
void reset_peak_rss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
}
double peak_rss_mib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  return 0.0;
}

// Bytes per point of a map gathered in memory for its Draco file (positions and intensity).
constexpr double kGatheredBytesPerPoint = 16.0;
// Finest LOD tiles hold at most this many points (1.6 MB .pnts files).
constexpr size_t kLodMaxPointsPerTile = 100000;

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
    for (size_t k = 0; k < options.sensors.size(); ++k) {
      const std::string& name = options.sensors[k];
      // Listed twice, its scans would go into its map twice.
      if (std::find(options.sensors.begin(), options.sensors.begin() + k, name) !=
          options.sensors.begin() + k)
        throw ContractError("options.map.sensors: '" + name + "' is listed twice");
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
    // Its files would be the combined map's (map_combined.drc/.ply), written concurrently.
    if (spec->name == kCombinedMapName)
      throw ContractError("sensor '" + spec->name + "': the name is reserved for the combined " +
                          "map (map_" + kCombinedMapName + ".drc); rename the sensor in " +
                          "mission.yaml");
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
  // map_<a>_preview.drc would be both a's (or the combined map's) preview and b's map.
  for (const auto& b : selection.mapped) {
    bool clash = b.name == std::string(kCombinedMapName) + "_preview";
    for (const auto& a : selection.mapped) clash = clash || b.name == a.name + "_preview";
    if (clash)
      throw ContractError("sensor '" + b.name + "': map_" + b.name +
                          ".drc would also name a preview; rename the sensor in mission.yaml");
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

// Estimates per map point, measured on the keel-sim bridge (14.4 M points in the combined map;
// the times again on the 220 s bridge, 10.7 M, from the job log's task lines): a sensor's Draco
// file (gathering its tiles, the encoding, the round trip and the preview) ~0.5 us and, at its
// peak, ~48 bytes (Draco's copy of the input, its quantized attributes and the kd-tree's copy
// of them, the output); the metrics (20000 query points) ~0.15 us and ~29 bytes (the cell
// grid); a PLY ~0.05 us (mostly the kernel's copy) and a buffer of fixed size. The costs order
// the tasks, costliest first: the round trip of the combined map, which can only start once
// its encoding ends, was estimated at half its cost (0.1 us) and so waited 1.3 s behind
// shorter tasks at the end of the stage.
constexpr double kDracoSecondsPerPoint = 0.5e-6;
constexpr double kDracoBytesPerPoint = 48.0;
// The two steps of a Draco file on their own: the encoding (gathering, encoding, preview; same
// peak), and the round trip (~0.22 us; the decoder's quantized and float copies, ~32 bytes,
// and the file's ~3.6).
constexpr double kDracoEncodeSecondsPerPoint = 0.35e-6;
constexpr double kDracoCheckSecondsPerPoint = 0.22e-6;
constexpr double kDracoCheckBytesPerPoint = 35.0;
constexpr double kMetricsSecondsPerPoint = 0.15e-6;
constexpr double kMetricsBytesPerPoint = 29.0;
constexpr double kPlySecondsPerPoint = 0.05e-6;
// LOD tiles: the octree's splits and thinning, the .pnts encoding (estimate, per map point).
constexpr double kLodSecondsPerPoint = 0.15e-6;

// One map's artifacts and their figures for the report.
struct MapOutput {
  json report = json::object();
  std::vector<std::string> artifacts;
};

// A preview (map_outputs.h) as a map output: report {"preview": {...}}.
MapOutput preview_output(PreviewOutput preview) {
  return {{{"preview", std::move(preview.report)}}, std::move(preview.artifacts)};
}

// Per-point metrics of a whole map (every point a query point, ~1600 neighbours each within
// 0.25 m on a 2 cm map): ~4 us and the cell grid per point, plus 12 bytes of fields.
constexpr double kPointMetricsSecondsPerPoint = 4e-6;
constexpr double kPointMetricsBytesPerPoint = kMetricsBytesPerPoint + 12.0;
// A preview's thinned copy (~20 bytes per point) and its encoding.
constexpr double kPreviewBytesPerPoint = kDracoBytesPerPoint + 20.0;

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
  out.artifacts.push_back(
      write_draco_sidecar(work_dir, map_draco_file(name), encoded.summary, "world",
                          preview_entry(name, points, options.preview_max_points)));
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
                  {"encode_seconds", earlier_seconds + seconds_since(start)}}},
                {"sidecar", out.artifacts.back()}};
  return out;
}

// Writes map_<name>.ply from the tiles of `parts`; report {"ply": {...}}.
MapOutput write_tiled_map_ply(TiledMaps& tiled, const std::vector<std::string>& parts,
                              const std::string& name, const fs::path& work_dir,
                              const std::function<void()>& check_canceled) {
  MapOutput out;
  write_tiled_ply(tiled, parts, tiled.output_partition(parts), work_dir / map_ply_file(name),
                  check_canceled);
  out.artifacts.push_back(map_ply_file(name));
  out.report["ply"] = {{"file", map_ply_file(name)},
                       {"bytes", fs::file_size(work_dir / map_ply_file(name))}};
  return out;
}

// Writes tiles_<name>.tar, the LOD tileset of `parts`; report {"tiles": {...}}.
MapOutput write_map_tiles(TiledMaps& tiled, const std::vector<std::string>& parts,
                          const std::string& name, const fs::path& work_dir,
                          const std::function<void()>& check_canceled) {
  mapping::LodOptions lod;
  lod.max_points_per_tile = kLodMaxPointsPerTile;
  lod.min_edge_m = tiled.output_grid().unit_m();
  const MapTilesetResult result =
      write_tiled_tileset(tiled, parts, tiled.output_partition(parts), name,
                          work_dir / map_tiles_file(name), lod, check_canceled);
  MapOutput out;
  out.artifacts.push_back(map_tiles_file(name));
  out.report["tiles"] = {
      {"file", map_tiles_file(name)}, {"format", "3D Tiles 1.0, pnts (docs/artifacts.md)"},
      {"tiles", result.tiles},        {"points", result.points},
      {"bytes", result.bytes},        {"max_points_per_tile", lod.max_points_per_tile},
      {"seconds", result.seconds}};
  return out;
}

// A map whose single Draco file would not fit the memory budget: its report says so.
MapOutput draco_not_written(size_t points, double needed_bytes, double budget_bytes) {
  MapOutput out;
  out.report = {{"points", points},
                {"draco",
                 {{"written", false},
                  {"reason", "one Draco file of " + std::to_string(points) + " points needs ~" +
                                 std::to_string(static_cast<long long>(needed_bytes / (1 << 20))) +
                                 " MiB to encode, over the " +
                                 std::to_string(static_cast<long long>(budget_bytes / (1 << 20))) +
                                 " MiB the budget leaves the outputs (map.memory_budget_mb); "
                                 "the map is whole in its PLY file and LOD tiles"}}}};
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

// The metrics of the map made of `parts`, from its tiles.
MetricsColumn measure_tiled(const std::string& name, TiledMaps& tiled,
                            const std::vector<std::string>& parts, const MapStageOptions& options,
                            const StageContext& context) {
  mapping::MapMetricsOptions metrics_options;
  metrics_options.check_canceled = [&context] { context.check_canceled(); };
  metrics_options.radius_m = options.metrics_radius_m;
  metrics_options.threads = options.threads;
  metrics_options.max_query_points = options.metrics_max_points;
  const auto start = std::chrono::steady_clock::now();
  MetricsColumn column{
      name, tiled_map_metrics(tiled, parts, tiled.output_partition(parts), metrics_options), 0.0};
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

// The mapping settings of the selected sensors (their filter chains), before the TF tree.
mapping::MapBuilderOptions map_builder_options(const MapStageOptions& options,
                                               const SensorSelection& selection) {
  mapping::MapBuilderOptions builder_options;
  builder_options.scans_per_intermediary = options.scans_per_intermediary;
  builder_options.final_voxel_merge_radius_leaves = options.final_voxel_merge_radius_leaves;
  builder_options.deskew.max_sweep_duration_s = options.max_sweep_duration_s;
  builder_options.threads = options.threads;
  for (const auto& s : selection.mapped)
    builder_options.sensors[s.name] = options.sensor_options(s.name, s.type);
  return builder_options;
}

// The lidar whose keyframe scans build the SLAM-map baseline: `slam_sensor`, else the first
// lidar mapped; nullptr when no lidar is mapped.
const MappedSensor* find_slam_sensor(const MapStageOptions& options,
                                     const SensorSelection& selection) {
  for (const auto& s : selection.mapped)
    if (options.slam_sensor.empty() ? s.type == "lidar" : s.name == options.slam_sensor) return &s;
  if (!options.slam_sensor.empty())
    throw ContractError("options.map.slam_sensor: '" + options.slam_sensor +
                        "' is not among the mapped sensors");
  return nullptr;
}

// One run of the stage, as the steps of the header comment; members hold what the steps pass
// on. The output tasks capture members by reference, so `runner_`, which joins them on an
// exception, is declared last (destroyed first).
class MapRun {
 public:
  explicit MapRun(StageContext& context)
      : context_(context),
        stage_start_(std::chrono::steady_clock::now()),
        options_(MapStageOptions::from_json(context.options)) {
    reset_peak_rss();
  }

  StageResult run() {
    try {
      return run_steps();
    } catch (...) {
      remove_written_maps();
      throw;
    }
  }

 private:
  StageResult run_steps() {
    io::MissionReader reader(io::load_mission(context_.mission_dir));
    choose_sensors(reader);
    prepare_mapping(reader);
    scan_every_sensor(reader);
    StageResult out;
    json& r = out.report;
    r["options"] = options_.to_json();
    r["poses"] = poses_.report;
    r["skipped_sensors"] = selection_.skipped;
    outputs_start_ = std::chrono::steady_clock::now();
    outputs_cpu_start_ = process_cpu_seconds();
    r["sensors"] = describe_sensors();
    r["slam_map"] = describe_slam_map();
    run_outputs();
    collect_artifacts(out);
    r["metrics"] = metrics_report();
    r["timing"] = timing_report();
    r["memory"] = memory_report();
    r["warnings"] = warnings_;
    task_log_->flush(context_.log);
    context_.log("map: outputs and metrics " + std::to_string(seconds_since(outputs_start_)) +
                 " s wall, " + std::to_string(process_cpu_seconds() - outputs_cpu_start_) +
                 " s cpu");
    context_.progress(1.0);
    return out;
  }

  // Step 1: the sensors to map (the options were read by the constructor); every
  // sensor_filters entry must name one of them.
  void choose_sensors(const io::MissionReader& reader) {
    selection_ = select_sensors(reader, options_);
    for (const auto& item : options_.sensor_filters.items()) {
      const bool mapped = std::any_of(selection_.mapped.begin(), selection_.mapped.end(),
                                      [&](const MappedSensor& s) { return s.name == item.key(); });
      if (mapped) continue;
      std::vector<std::string> names;
      for (const auto& s : selection_.mapped) names.push_back(s.name);
      throw ContractError("options.map.sensor_filters." + item.key() +
                          ": no such sensor is mapped (mapped: " + join_names(names) + ")");
    }
    context_.check_canceled();
  }

  // Step 2: poses, the TF tree, one MapBuilder per sensor and the SLAM-map baseline.
  void prepare_mapping(const io::MissionReader& reader) {
    poses_ = build_poses(reader, options_, context_);
    tree_.emplace(poses_.T_world_body, "map poses");
    builder_options_ = map_builder_options(options_, selection_);
    make_tiled_maps();
    for (const auto& s : selection_.mapped) tree_->set_extrinsic(s.name, s.T_body_sensor);
    // One MapBuilder per sensor (a sensor's map depends on its own scans only, Fig. 5): a
    // sensor's outputs start once its last scan is in, while the next sensors scan.
    for (const auto& s : selection_.mapped) {  // names are unique (select_sensors)
      mapping::MapBuilderOptions one = builder_options_;
      one.sensors = {{s.name, builder_options_.sensors.at(s.name)}};
      builders_.emplace(s.name, std::make_unique<mapping::MapBuilder>(*tree_, std::move(one)));
    }
    // The SLAM-map baseline: the SLAM lidar's scans at the SLAM system's keyframes.
    slam_sensor_ = find_slam_sensor(options_, selection_);
    if (slam_sensor_) {
      mapping::SlamMapOptions slam_options;
      slam_options.keyframe_leaf_m = options_.slam_keyframe_leaf_m;
      slam_.emplace(poses_.slam_keyframes, slam_sensor_->T_body_sensor, slam_options, &*tree_,
                    slam_sensor_->name);
    }
  }

  // Step 3: every scan of every sensor. As soon as a sensor's last scan is in, its outputs
  // (steps 4 and 5) start on one extra thread while the next sensors scan.
  void scan_every_sensor(const io::MissionReader& reader) {
    // Scan counts are known up front (index.csv / bag), for the progress.
    std::vector<std::unique_ptr<io::ScanSource>> sources;
    size_t total_scans = 0;
    for (const auto& s : selection_.mapped) {
      sources.push_back(reader.open_scans(s.name));
      total_scans += sources.back()->size();
    }
    context_.log("map: " + std::to_string(total_scans) + " scans of " +
                 std::to_string(selection_.mapped.size()) + " sensors, " +
                 std::to_string(poses_.T_world_body.size()) + " poses");
    const auto scans_start = std::chrono::steady_clock::now();
    task_log_.emplace(scans_start, "map: output task");
    for (const auto& s : selection_.mapped) {  // result slots, made before any task runs
      drc_[s.name];
      ply_[s.name];
      tiles_[s.name];
      preview_[s.name];
    }
    runner_.emplace(*task_log_);
    // Early outputs take one thread beside the scans' `threads` (none when threads = 1).
    const bool early_outputs = options_.threads >= 2;
    if (early_outputs) runner_->run_with(1, 0.0);
    size_t scans_done = 0;
    for (size_t k = 0; k < sources.size(); ++k) {
      scan_sensor(selection_.mapped[k], *sources[k], total_scans, scans_done);
      sources[k].reset();
      context_.check_canceled();
      runner_->rethrow_if_failed();  // an earlier sensor's output failed: stop scanning
      finish_sensor(selection_.mapped[k], early_outputs && k + 1 < sources.size());
    }
    context_.check_canceled();
    scans_seconds_ = seconds_since(scans_start);
    for (const auto& [name, builder] : builders_)
      if (!builder->sensors().empty()) built_.push_back(name);
    for (const auto& name : built_) points_in_ += builders_.at(name)->stats(name).points_in;
    context_.log("map: " + std::to_string(points_in_) + " points in " +
                 std::to_string(scans_seconds_) + " s");
  }

  // MapBuilder pulls the sensor's scans from this feed on options.threads threads (calls never
  // overlap, so the source, the SLAM baseline and progress see scans one at a time, in order).
  void scan_sensor(const MappedSensor& sensor, io::ScanSource& source, size_t total_scans,
                   size_t& scans_done) {
    try {
      feed_sensor(sensor, source, total_scans, scans_done);
    } catch (const std::invalid_argument& e) {  // e.g. a voxel index overflow: say whose
      throw std::invalid_argument("map: sensor '" + sensor.name + "': " + e.what());
    }
  }

  void feed_sensor(const MappedSensor& sensor, io::ScanSource& source, size_t total_scans,
                   size_t& scans_done) {
    builders_.at(sensor.name)->add_scans([&](std::string& sensor_name, PointCloud& scan) {
      context_.check_canceled();
      if (!source.next(scan)) return false;
      sensor_name = sensor.name;
      if (slam_ && &sensor == slam_sensor_) slam_->add_scan(scan);
      ++scans_done;
      if (total_scans > 0)
        context_.progress(kScansDone * static_cast<double>(scans_done) / total_scans);
      return true;
    });
  }

  // A sensor's scans are all in: its map (and the SLAM map) are final; `start_outputs`: queue
  // their tasks now, beside the next sensors' scans.
  void finish_sensor(const MappedSensor& sensor, bool start_outputs) {
    mapping::MapBuilder& builder = *builders_.at(sensor.name);
    builder.finish();
    if (!builder.sensors().empty()) {
      // With the merge rule the builder made the final map; it goes to the tiles whole.
      if (merging()) tiled_->add_final_input(sensor.name, builder.sensor_map(sensor.name));
      filter_tiles(sensor.name);
    }
    const bool is_slam_sensor = slam_ && sensor.name == slam_sensor_->name;
    if (is_slam_sensor) {
      const PointCloud slam_map = slam_->finish();
      slam_points_ = slam_map.size();
      tiled_->add_slam_points(slam_map);
      tiled_->finish_slam();
    }
    if (!start_outputs) return;
    if (!builders_.at(sensor.name)->sensors().empty()) {
      runner_->add(guarded(sensor_tasks(sensor.name)));
      output_queued_.push_back(sensor.name);
    }
    if (is_slam_sensor) {
      runner_->add(guarded(slam_tasks()));
      slam_queued_ = true;
    }
  }

  bool merging() const { return options_.final_voxel_merge_radius_leaves > 0.0; }

  // The out-of-core maps: each sensor's final chain runs on its tiles (with the merge rule,
  // which depends on the order of the whole stream, the builder runs it and the tiles only
  // hold the result).
  void make_tiled_maps() {
    const double budget = static_cast<double>(options_.memory_budget_mb) * (1 << 20);
    const TiledMapsOptions tiles =
        tiled_maps_options_for_budget(budget, options_.threads, options_.metrics_radius_m);
    std::vector<std::pair<std::string, mapping::FilterChain>> chains;
    for (const auto& s : selection_.mapped)
      chains.emplace_back(s.name, merging() ? mapping::FilterChain{}
                                            : builder_options_.sensors.at(s.name).final_filters);
    tiled_ = std::make_unique<TiledMaps>(context_.work_dir, chains, tiles);
    output_budget_ = budget * kOutputShare;
    if (!merging())
      builder_options_.final_sink = [this](const std::string& sensor, const PointCloud& points) {
        tiled_->add_final_input(sensor, points);
      };
  }

  // The sensor's final filters over its tiles; a budget too small for a tile names the option.
  void filter_tiles(const std::string& sensor) {
    try {
      tiled_->filter_sensor(sensor, [this] { context_.check_canceled(); });
    } catch (const TileBudgetError& e) {
      throw_budget_error(e);
    }
  }

  [[noreturn]] void throw_budget_error(const TileBudgetError& e) const {
    const double minimum_mb =
        std::ceil(e.minimum_bytes() * options_.threads / kTileShare / (1 << 20));
    throw ContractError(
        "options.map.memory_budget_mb: " + std::to_string(options_.memory_budget_mb) +
        " MiB cannot hold one tile (" + e.what() + "); the smallest budget that would work is " +
        std::to_string(static_cast<long long>(minimum_mb)) + " MiB");
  }

  size_t map_points(const std::string& name) const { return tiled_->points(name); }

  // The builder's counts with the final stage as the tiles ran it (the whole map's counts).
  mapping::SensorMapStats sensor_stats(const std::string& name) const {
    mapping::SensorMapStats stats = builders_.at(name)->stats(name);
    if (!merging()) {
      const TiledFilterStats& tiled = tiled_->filter_stats(name);
      stats.final_stage.applications = tiled.tiles;
      stats.final_stage.steps = tiled.steps;
    }
    stats.points_out = map_points(name);
    return stats;
  }

  // The report's `sensors` section (filters, stats, warnings_). Sets written_: the sensors
  // with a non-empty map, largest first.
  json describe_sensors() {
    json sensors = json::object();
    for (const auto& s : selection_.mapped) {
      json entry = {{"type", s.type},
                    {"filters", mapping::to_json(builder_options_.sensors.at(s.name))}};
      if (std::find(built_.begin(), built_.end(), s.name) == built_.end()) {
        entry["stats"] = nullptr;
        warnings_.push_back("sensor '" + s.name + "': no scans");
        sensors[s.name] = entry;
        continue;
      }
      const mapping::SensorMapStats stats = sensor_stats(s.name);
      entry["stats"] = stats_json(stats);
      entry["tiles"] = filter_tiles_json(s.name);
      if (map_points(s.name) == 0) {
        warnings_.push_back("sensor '" + s.name + "': the map is empty (every point filtered, " +
                            "or every scan outside the trajectory); no artifacts written");
      } else if (std::find(written_.begin(), written_.end(), s.name) == written_.end()) {
        written_.push_back(s.name);
      }
      if (stats.scans_outside_trajectory > 0)
        warnings_.push_back("sensor '" + s.name +
                            "': " + std::to_string(stats.scans_outside_trajectory) +
                            " scans outside the trajectory were skipped");
      if (const std::string w = emptied_by(stats); !w.empty())
        warnings_.push_back("sensor '" + s.name + "': " + w);
      sensors[s.name] = entry;
    }
    std::stable_sort(
        written_.begin(), written_.end(),
        [&](const std::string& a, const std::string& b) { return map_points(a) > map_points(b); });
    return sensors;
  }

  // The report's `slam_map` section (null without a lidar), with its warnings.
  json describe_slam_map() {
    if (!slam_) {
      warnings_.push_back("no lidar mapped: no SLAM-map baseline");
      return nullptr;
    }
    if (slam_points_ == 0)
      warnings_.push_back("SLAM map: no scan of '" + slam_sensor_->name +
                          "' matches a keyframe; no baseline");
    return {{"sensor", slam_sensor_->name},
            {"keyframes", slam_->keyframes()},
            {"keyframes_used", slam_->keyframes_used()},
            {"keyframe_leaf_m", options_.slam_keyframe_leaf_m},
            {"points", slam_points_}};
  }

  // Steps 4 and 5: the tasks not started during the scans and the combined map's, costliest
  // first on `threads` threads under a memory budget. The combined map (Eq. (21)) is kept as
  // its parts, the sensor maps in name order (MapBuilder's), never copied whole.
  void run_outputs() {
    for (const auto& name : built_) {
      if (map_points(name) == 0) continue;
      combined_parts_.push_back(name);
      combined_attributes_.part_labels.push_back(name);
      combined_points_ += map_points(name);
    }
    if (combined_points_ == 0)
      throw std::runtime_error("map: every map is empty; nothing to write");
    if (slam_ && std::find(written_.begin(), written_.end(), slam_sensor_->name) != written_.end())
      primary_ = "inspection_" + slam_sensor_->name;

    std::vector<OutputTask> tasks;
    for (const auto& name : built_) {
      if (std::find(output_queued_.begin(), output_queued_.end(), name) != output_queued_.end())
        continue;
      for (auto& task : sensor_tasks(name)) tasks.push_back(std::move(task));
    }
    if (slam_ && !slam_queued_)
      for (auto& task : slam_tasks()) tasks.push_back(std::move(task));
    for (auto& task : combined_tasks()) tasks.push_back(std::move(task));
    runner_->add(guarded(std::move(tasks)));
    // Memory: the tasks' estimates within the budget's output share (tile tasks hold a tile
    // per thread, a Draco task its whole map).
    runner_->run_with(options_.threads, output_budget_);
    try {
      runner_->finish([&](double f) { context_.progress(kScansDone + (1.0 - kScansDone) * f); });
    } catch (const TileBudgetError& e) {
      throw_budget_error(e);
    }
    context_.check_canceled();
  }

  // Tasks that first check for a cancel request, so a canceled job starts no further output.
  std::vector<OutputTask> guarded(std::vector<OutputTask> tasks) const {
    for (auto& task : tasks)
      task.run = [&context = context_, run = std::move(task.run)] {
        context.check_canceled();
        run();
      };
    return tasks;
  }

  std::function<void()> cancel_check() const {
    return [this] { context_.check_canceled(); };
  }

  // Bytes of a Draco file of n points made in memory (the map gathered, then encoded), or 0
  // when it would not fit the budget's output share.
  // With write_point_metrics the metrics' grid and fields, and a large map's preview, are made
  // in the same task from the same gathered map.
  double draco_bytes(size_t points) const {
    const double n = static_cast<double>(points);
    double bytes = (kGatheredBytesPerPoint + kDracoBytesPerPoint) * n;
    if (options_.write_point_metrics) bytes += kPointMetricsBytesPerPoint * n;
    if (wants_preview(points))
      bytes += kPreviewBytesPerPoint * static_cast<double>(options_.preview_max_points);
    return bytes;
  }
  // Seconds of the same (before the combined map's check).
  double draco_seconds(size_t points, double encode_seconds_per_point) const {
    const double n = static_cast<double>(points);
    double seconds = encode_seconds_per_point * n;
    if (options_.write_point_metrics) seconds += kPointMetricsSecondsPerPoint * n;
    if (wants_preview(points))
      seconds += kDracoSecondsPerPoint * static_cast<double>(options_.preview_max_points);
    return seconds;
  }

  // Per-point metrics (Eqs. 23-26) of positions as Draco fields, into `attributes`.
  void add_point_metrics(const std::vector<Eigen::Vector3f>& xyz,
                         io::PartsAttributes& attributes) const {
    mapping::MapMetricsOptions metrics;
    metrics.check_canceled = cancel_check();
    metrics.radius_m = options_.metrics_radius_m;
    metrics.threads = options_.threads;
    PointMetricFields fields = point_metric_fields(xyz, metrics);
    attributes.fields = std::move(fields.fields);
    attributes.fields_no_data = std::move(fields.no_data);
  }

  // map_<name>_preview.drc of a map larger than preview_max_points, from its gathered parts.
  MapOutput write_preview(const std::vector<const PointCloud*>& parts,
                          const io::PartsAttributes& attributes, const std::string& name) const {
    return preview_output(write_map_preview(parts, attributes, options_.preview_max_points,
                                            draco_options(options_), map_preview_file(name),
                                            context_.work_dir));
  }
  bool draco_fits(size_t points) const { return draco_bytes(points) <= output_budget_; }
  bool wants_preview(size_t points) const {
    return options_.preview_max_points > 0 && points > options_.preview_max_points;
  }

  // The tasks of a sensor whose map is built, each reading its tiles: the LOD tiles, the PLY
  // file, the Draco file when the map fits the budget (gathered in memory), and the
  // inspection map's metrics for the SLAM lidar. Results land in the slots made before the
  // scans.
  std::vector<OutputTask> sensor_tasks(const std::string& name) {
    std::vector<OutputTask> tasks;
    const size_t n = map_points(name);
    if (n == 0) return tasks;
    const double tile_bytes = static_cast<double>(tiled_->options().tile_budget_bytes);
    if (draco_fits(n)) {
      tasks.push_back({"draco " + name, draco_seconds(n, kDracoSecondsPerPoint), draco_bytes(n),
                       [this, name, n] {
                         const auto start = std::chrono::steady_clock::now();
                         const std::vector<std::string> parts = {name};
                         const PointCloud map =
                             gather_tiled_map(*tiled_, parts, tiled_->output_partition(parts));
                         io::PartsAttributes attributes;
                         if (options_.write_point_metrics) add_point_metrics(map.xyz, attributes);
                         drc_.at(name) =
                             write_map_draco(io::encode_draco_point_cloud(
                                                 {&map}, draco_options(options_), attributes),
                                             n, start, 0.0, name, options_, context_.work_dir);
                         if (wants_preview(n))
                           preview_.at(name) = write_preview({&map}, attributes, name);
                       }});
    } else {
      drc_.at(name) = draco_not_written(n, draco_bytes(n), output_budget_);
      warnings_.push_back("sensor '" + name +
                          "': " + drc_.at(name).report["draco"]["reason"].get<std::string>());
    }
    if (options_.write_ply)
      tasks.push_back({"ply " + name, kPlySecondsPerPoint * n, tile_bytes, [this, name] {
                         ply_.at(name) = write_tiled_map_ply(*tiled_, {name}, name,
                                                             context_.work_dir, cancel_check());
                       }});
    if (options_.write_tiles)
      tasks.push_back({"tiles " + name, kLodSecondsPerPoint * n, tile_bytes, [this, name] {
                         tiles_.at(name) = write_map_tiles(*tiled_, {name}, name, context_.work_dir,
                                                           cancel_check());
                       }});
    if (slam_ && name == slam_sensor_->name)
      tasks.push_back({"metrics inspection_" + name, kMetricsSecondsPerPoint * n,
                       tile_bytes * options_.threads, [this, name] {
                         inspection_ = measure_tiled("inspection_" + name, *tiled_, {name},
                                                     options_, context_);
                       }});
    return tasks;
  }

  std::vector<OutputTask> slam_tasks() {
    std::vector<OutputTask> tasks;
    if (slam_points_ > 0)
      tasks.push_back(
          {"metrics slam_map", kMetricsSecondsPerPoint * slam_points_,
           static_cast<double>(tiled_->options().tile_budget_bytes) * options_.threads, [this] {
             slam_column_ = measure_tiled("slam_map", *tiled_, {"slam"}, options_, context_);
           }});
    return tasks;
  }

  // The combined map (Eq. (21)) from every sensor's tiles: its LOD tiles, PLY and metrics, and
  // its Draco file when it fits the budget (the sensor maps gathered as its parts; the encoding
  // adds its round trip, the check, as a task of its own).
  std::vector<OutputTask> combined_tasks() {
    std::vector<OutputTask> tasks;
    const double n_combined = static_cast<double>(combined_points_);
    const double tile_bytes = static_cast<double>(tiled_->options().tile_budget_bytes);
    if (draco_fits(combined_points_)) {
      tasks.push_back(
          {"draco combined (encode)", draco_seconds(combined_points_, kDracoEncodeSecondsPerPoint),
           draco_bytes(combined_points_), [this] {
             const auto start = std::chrono::steady_clock::now();
             for (const auto& name : combined_parts_) {
               const std::vector<std::string> parts = {name};
               combined_maps_.push_back(
                   gather_tiled_map(*tiled_, parts, tiled_->output_partition(parts)));
             }
             std::vector<const PointCloud*> parts;
             for (const auto& map : combined_maps_) parts.push_back(&map);
             if (options_.write_point_metrics) {
               std::vector<Eigen::Vector3f> positions;
               positions.reserve(combined_points_);
               for (const PointCloud* part : parts)
                 positions.insert(positions.end(), part->xyz.begin(), part->xyz.end());
               add_point_metrics(positions, combined_attributes_);
             }
             combined_encoded_ = io::encode_draco_point_cloud_bytes(parts, draco_options(options_),
                                                                    combined_attributes_);
             if (wants_preview(combined_points_))
               combined_preview_ = write_preview(parts, combined_attributes_, kCombinedMapName);
             combined_encode_seconds_ = seconds_since(start);
             runner_->add(guarded({combined_draco_check()}));
           }});
    } else {
      combined_output_ =
          draco_not_written(combined_points_, draco_bytes(combined_points_), output_budget_);
      warnings_.push_back("combined map: " +
                          combined_output_.report["draco"]["reason"].get<std::string>());
    }
    if (options_.write_ply)
      tasks.push_back({"ply combined", kPlySecondsPerPoint * n_combined, tile_bytes, [this] {
                         combined_ply_ =
                             write_tiled_map_ply(*tiled_, combined_parts_, kCombinedMapName,
                                                 context_.work_dir, cancel_check());
                       }});
    if (options_.write_tiles)
      tasks.push_back({"tiles combined", kLodSecondsPerPoint * n_combined, tile_bytes, [this] {
                         combined_tiles_ =
                             write_map_tiles(*tiled_, combined_parts_, kCombinedMapName,
                                             context_.work_dir, cancel_check());
                       }});
    tasks.push_back({"metrics inspection_combined", kMetricsSecondsPerPoint * n_combined,
                     tile_bytes * options_.threads, [this] {
                       combined_column_ = measure_tiled("inspection_combined", *tiled_,
                                                        combined_parts_, options_, context_);
                     }});
    return tasks;
  }

  // The combined Draco file's round trip (the error it reports), then the file itself.
  OutputTask combined_draco_check() {
    const double n_combined = static_cast<double>(combined_points_);
    return {"draco combined (check)", kDracoCheckSecondsPerPoint * n_combined,
            (kGatheredBytesPerPoint + kDracoCheckBytesPerPoint) * n_combined, [this] {
              const auto start = std::chrono::steady_clock::now();
              std::vector<const PointCloud*> parts;
              for (const auto& map : combined_maps_) parts.push_back(&map);
              io::measure_draco_point_cloud(parts, draco_options(options_), &combined_encoded_);
              combined_output_ = write_map_draco(combined_encoded_, combined_points_, start,
                                                 combined_encode_seconds_, kCombinedMapName,
                                                 options_, context_.work_dir);
              combined_encoded_ = io::DracoEncoded{};
              combined_maps_.clear();
              combined_maps_.shrink_to_fit();
            }};
  }

  // The per-sensor maps' (largest first) and the combined map's files and report sections.
  void collect_artifacts(StageResult& out) {
    for (const auto& name : written_) {
      MapOutput& map_output = drc_.at(name);
      merge_output(map_output, ply_.at(name));
      merge_output(map_output, tiles_.at(name));
      merge_output(map_output, preview_.at(name));
      out.report["sensors"][name]["map"] = map_output.report;
      out.artifacts.insert(out.artifacts.end(), map_output.artifacts.begin(),
                           map_output.artifacts.end());
    }
    merge_output(combined_output_, combined_ply_);
    merge_output(combined_output_, combined_tiles_);
    merge_output(combined_output_, combined_preview_);
    if (!combined_output_.report.contains("points"))
      combined_output_.report["points"] = combined_points_;
    out.report["combined"] = combined_output_.report;
    out.artifacts.insert(out.artifacts.end(), combined_output_.artifacts.begin(),
                         combined_output_.artifacts.end());
  }

  // After a failure: the map files written so far go, so none can pass for a finished map
  // (a sensor's outputs start while later sensors still scan). The output tasks are joined
  // first; they record what they wrote in drc_, ply_ and the combined outputs.
  void remove_written_maps() {
    runner_.reset();
    std::vector<const MapOutput*> outputs = {&combined_output_, &combined_ply_, &combined_tiles_,
                                             &combined_preview_};
    for (const auto* by_sensor : {&drc_, &ply_, &tiles_, &preview_})
      for (const auto& [name, output] : *by_sensor) outputs.push_back(&output);
    std::error_code ignored;  // best effort: the stage's own error is the one to report
    for (const MapOutput* output : outputs)
      for (const auto& file : output->artifacts) fs::remove(context_.work_dir / file, ignored);
  }

  // Step 5's report: each map's metrics (Eqs. (23)-(26)) and Table V.
  json metrics_report() {
    std::vector<MetricsColumn> columns;
    for (auto* column : {&slam_column_, &inspection_, &combined_column_})
      if (*column) columns.push_back(std::move(**column));
    json metrics = {{"radius_m", options_.metrics_radius_m},
                    {"max_query_points", options_.metrics_max_points},
                    {"maps", json::object()}};
    for (const auto& c : columns) {
      metrics["maps"][c.name] = mapping::to_json(c.metrics);
      metrics["maps"][c.name]["seconds"] = c.seconds;
      metrics_seconds_ += c.seconds;
      metrics_queries_ += c.metrics.query_points;
    }
    metrics["table_v"] = table_v(columns, primary_);
    return metrics;
  }

  json filter_tiles_json(const std::string& name) const {
    const TiledFilterStats& t = tiled_->filter_stats(name);
    return {{"filter_tiles", t.tiles},
            {"splits", t.splits},
            {"halo_points", t.halo_points},
            {"largest_tile_points", t.largest_tile_points}};
  }

  // Report 4 of issue 17: the stage's peak memory against its budget, what was spilled.
  json memory_report() const {
    const io::SpillStore& store = tiled_->store();
    const double mib = 1 << 20;
    return {{"budget_mb", options_.memory_budget_mb},
            {"peak_rss_mib", peak_rss_mib()},
            {"spill_buffer_budget_mib", static_cast<double>(store.buffer_budget()) / mib},
            {"spill_buffered_peak_mib", static_cast<double>(store.peak_bytes_buffered()) / mib},
            {"bytes_spilled", store.bytes_spilled()},
            {"tile_budget_mib", static_cast<double>(tiled_->options().tile_budget_bytes) / mib},
            {"output_budget_mib", output_budget_ / mib}};
  }

  json timing_report() const {
    const double stage_seconds = seconds_since(stage_start_);
    return {{"stage_seconds", stage_seconds},
            {"stage_input_points_per_second", stage_seconds > 0 ? points_in_ / stage_seconds : 0.0},
            {"outputs_and_metrics_seconds", seconds_since(outputs_start_)},
            {"threads", options_.threads},
            {"scans_seconds", scans_seconds_},
            {"input_points", points_in_},
            {"input_points_per_second", scans_seconds_ > 0 ? points_in_ / scans_seconds_ : 0.0},
            {"metrics_seconds", metrics_seconds_},
            {"metrics_query_points_per_second",
             metrics_seconds_ > 0 ? metrics_queries_ / metrics_seconds_ : 0.0}};
  }

  StageContext& context_;
  const std::chrono::steady_clock::time_point stage_start_;
  const MapStageOptions options_;
  // Steps 1 and 2.
  SensorSelection selection_;
  Poses poses_;
  std::optional<mapping::TransformTree> tree_;  // the builders and the SLAM baseline read it
  mapping::MapBuilderOptions builder_options_;
  std::map<std::string, std::unique_ptr<mapping::MapBuilder>> builders_;
  const MappedSensor* slam_sensor_ = nullptr;  // in selection_.mapped
  std::optional<mapping::SlamMapBuilder> slam_;
  std::unique_ptr<TiledMaps> tiled_;  // the maps, out of core
  double output_budget_ = 0.0;        // bytes the output tasks may hold at once
  // Step 3.
  size_t slam_points_ = 0;
  std::vector<std::string> built_;  // sensors that had scans, in name order
  size_t points_in_ = 0;
  double scans_seconds_ = 0.0;
  std::vector<std::string> output_queued_;  // sensors whose tasks started during the scans
  bool slam_queued_ = false;
  // Steps 4 and 5: the report's pieces and the tasks' results.
  json warnings_ = json::array();
  std::vector<std::string> written_;             // sensors with a non-empty map, largest first
  std::string primary_ = "inspection_combined";  // Table V's inspection map
  std::chrono::steady_clock::time_point outputs_start_;
  double outputs_cpu_start_ = 0.0;
  std::map<std::string, MapOutput> drc_, ply_, tiles_, preview_;
  MapOutput combined_output_, combined_ply_, combined_tiles_, combined_preview_;
  std::vector<std::string> combined_parts_;  // the sensor maps of the combined map
  // Its Draco attributes: each point's sensor (label), and per-point metrics when written.
  io::PartsAttributes combined_attributes_{kSensorAttribute, {}, {}, {}};
  std::vector<PointCloud> combined_maps_;  // gathered for its Draco file
  size_t combined_points_ = 0;
  io::DracoEncoded combined_encoded_;
  double combined_encode_seconds_ = 0.0;
  std::optional<MetricsColumn> slam_column_, inspection_, combined_column_;
  double metrics_seconds_ = 0.0;
  size_t metrics_queries_ = 0;
  std::optional<TaskLog> task_log_;
  std::optional<OutputRunner> runner_;  // last: joins the tasks before what they use goes
};

class MapStage : public Stage {
 public:
  std::string name() const override { return "map"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::map_section(section);
  }
  StageResult run(StageContext& context) override { return MapRun(context).run(); }
};

}  // namespace


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
  o.write_point_metrics = r.optional<bool>("write_point_metrics", o.write_point_metrics);
  o.metrics_radius_m = r.optional<double>("metrics_radius_m", o.metrics_radius_m);
  const long long max_points =
      r.optional<long long>("metrics_max_points", static_cast<long long>(o.metrics_max_points));
  local_require(max_points >= 0, "metrics_max_points", "an integer >= 0 (0: every point)");
  o.metrics_max_points = static_cast<size_t>(max_points);
  o.slam_sensor = r.optional<std::string>("slam_sensor", o.slam_sensor);
  o.slam_keyframe_leaf_m = r.optional<double>("slam_keyframe_leaf_m", o.slam_keyframe_leaf_m);
  o.threads = r.optional<int>("threads", o.threads);
  o.memory_budget_mb = r.optional<int>("memory_budget_mb", o.memory_budget_mb);
  o.write_tiles = r.optional<bool>("write_tiles", o.write_tiles);
  const long long preview_max = r.optional<long long>(
      "preview_max_points",
      static_cast<long long>(o.write_tiles ? 0 : MapStageOptions::kDefaultPreviewPoints));
  local_require(preview_max == 0 || (preview_max >= 1000 && preview_max <= 1000000000LL),
          "preview_max_points", "0 (none) or an integer in [1000, 1e9]");
  o.preview_max_points = static_cast<size_t>(preview_max);
  r.finish();

  local_require(o.lidar_filters.is_object(), "lidar_filters",
          "an object {scan_filters, intermediary_filters, final_filters, deskew}");
  local_require(o.sonar_filters.is_object(), "sonar_filters",
          "an object {scan_filters, intermediary_filters, final_filters, deskew}");
  local_require(o.sensor_filters.is_object(), "sensor_filters",
          "an object {\"<sensor>\": {scan_filters, intermediary_filters, final_filters, deskew}}");
  local_require(std::isfinite(o.final_voxel_leaf_m) && o.final_voxel_leaf_m >= 0.0, "final_voxel_leaf_m",
          "a leaf in metres >= 0 (0: no final voxel grid)");
  local_require(o.final_voxel_merge_radius_leaves >= 0.0 &&
              o.final_voxel_merge_radius_leaves <= mapping::VoxelAccumulator::kMaxMergeLeaves,
          "final_voxel_merge_radius_leaves", "a radius in leaves in [0, 2] (0: no merging)");
  local_require(o.scans_per_intermediary >= 1 && o.scans_per_intermediary <= 100000,
          "scans_per_intermediary", "an integer in [1, 100000]");
  local_require(o.max_sweep_duration_s > 0.0, "max_sweep_duration_s", "> 0");
  local_require(o.draco_position_bits >= 1 && o.draco_position_bits <= 30, "draco_position_bits",
          "an integer in [1, 30]");
  local_require(o.draco_compression_level >= 0 && o.draco_compression_level <= 10,
          "draco_compression_level", "an integer in [0, 10]");
  local_require(std::isfinite(o.metrics_radius_m) && o.metrics_radius_m > 0.0 &&
              o.metrics_radius_m <= mapping::kMaxMetricsRadiusM,
          "metrics_radius_m",
          "a radius in metres in (0, " + std::to_string(mapping::kMaxMetricsRadiusM) +
              "] (Table V: 0.25)");
  local_require(std::isfinite(o.slam_keyframe_leaf_m) && o.slam_keyframe_leaf_m > 0.0,
          "slam_keyframe_leaf_m", "a leaf in metres > 0");
  local_require(o.threads >= 1 && o.threads <= 256, "threads", "an integer in [1, 256]");
  local_require(o.memory_budget_mb >= kMinMemoryBudgetMb && o.memory_budget_mb <= 1 << 20,
          "memory_budget_mb",
          "an integer in [" + std::to_string(kMinMemoryBudgetMb) +
              ", 1048576] (MiB; the spill buffers and a tile per thread need at least " +
              std::to_string(kMinMemoryBudgetMb) + ")");
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
          {"write_point_metrics", write_point_metrics},
          {"preview_max_points", preview_max_points},
          {"metrics_radius_m", metrics_radius_m},
          {"metrics_max_points", metrics_max_points},
          {"slam_sensor", slam_sensor},
          {"slam_keyframe_leaf_m", slam_keyframe_leaf_m},
          {"threads", threads},
          {"memory_budget_mb", memory_budget_mb},
          {"write_tiles", write_tiles}};
}

std::unique_ptr<Stage> make_map_stage() { return std::make_unique<MapStage>(); }

}  // namespace keel::pipeline
