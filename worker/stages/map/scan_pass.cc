#include "worker/stages/map/scan_pass.h"

#include <stdexcept>

namespace keel::pipeline {
namespace {

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

}  // namespace

ScanPass::ScanPass(const MapStageOptions& options, const SensorSelection& selection,
                   const Poses& poses, const std::filesystem::path& work_dir)
    : options_(options),
      selection_(selection),
      tree_(poses.T_world_body, "map poses"),
      builder_options_(map_builder_options(options, selection)) {
  // Each sensor's final chain runs on its tiles, unless the builder runs it (merging).
  std::vector<std::pair<std::string, mapping::FilterChain>> chains;
  for (const auto& s : selection.mapped)
    chains.emplace_back(s.name, merging() ? mapping::FilterChain{}
                                          : builder_options_.sensors.at(s.name).final_filters);
  const double budget = static_cast<double>(options.memory_budget_mb) * (1 << 20);
  tiled_ = std::make_unique<TiledMaps>(
      work_dir, chains,
      tiled_maps_options_for_budget(budget, options.threads, options.metrics_radius_m));
  if (!merging())
    builder_options_.final_sink = [this](const std::string& sensor, const PointCloud& points) {
      tiled_->add_final_input(sensor, points);
    };
  for (const auto& s : selection.mapped) tree_.set_extrinsic(s.name, s.T_body_sensor);
  for (const auto& s : selection.mapped) {  // names are unique (select_sensors)
    mapping::MapBuilderOptions one = builder_options_;
    one.sensors = {{s.name, builder_options_.sensors.at(s.name)}};
    builders_.emplace(s.name, std::make_unique<mapping::MapBuilder>(tree_, std::move(one)));
  }
  // The SLAM-map baseline: the SLAM lidar's scans at the SLAM system's keyframes.
  slam_sensor_ = find_slam_sensor(options, selection);
  if (slam_sensor_) {
    mapping::SlamMapOptions slam_options;
    slam_options.keyframe_leaf_m = options.slam_keyframe_leaf_m;
    slam_.emplace(poses.slam_keyframes, slam_sensor_->T_body_sensor, slam_options, &tree_,
                  slam_sensor_->name);
  }
}

size_t ScanPass::open_scans(const io::MissionReader& reader) {
  for (const auto& s : selection_.mapped) {
    sources_.push_back(reader.open_scans(s.name));
    total_scans_ += sources_.back()->size();
  }
  return total_scans_;
}

void ScanPass::scan_sensor(size_t k, const StageContext& context) {
  const MappedSensor& sensor = selection_.mapped[k];
  io::ScanSource& source = *sources_[k];
  // MapBuilder pulls the scans from this feed on `threads` threads; calls never overlap, so
  // the source, the baseline and the progress see the scans one at a time, in order.
  const auto feed = [&](std::string& sensor_name, PointCloud& scan) {
    context.check_canceled();
    if (!source.next(scan)) return false;
    sensor_name = sensor.name;
    if (slam_ && &sensor == slam_sensor_) slam_->add_scan(scan);
    ++scans_done_;
    if (total_scans_ > 0)
      context.progress(kScansDone * static_cast<double>(scans_done_) / total_scans_);
    return true;
  };
  try {
    builders_.at(sensor.name)->add_scans(feed);
  } catch (const std::invalid_argument& e) {  // e.g. a voxel index overflow: say whose
    throw std::invalid_argument("map: sensor '" + sensor.name + "': " + e.what());
  }
  sources_[k].reset();
  context.check_canceled();
}

void ScanPass::finish_sensor(size_t k, const StageContext& context) {
  const std::string& name = selection_.mapped[k].name;
  mapping::MapBuilder& builder = *builders_.at(name);
  builder.finish();
  if (!builder.sensors().empty()) {
    // With the merge rule the builder made the final map; it goes to the tiles whole.
    if (merging()) tiled_->add_final_input(name, builder.sensor_map(name));
    try {
      tiled_->filter_sensor(name, [&context] { context.check_canceled(); });
    } catch (const TileBudgetError& e) {
      throw_memory_budget_error(e, options_);
    }
  }
  if (slam_ && name == slam_sensor_->name) {
    const PointCloud slam_map = slam_->finish();
    slam_points_ = slam_map.size();
    tiled_->add_slam_points(slam_map);
    tiled_->finish_slam();
  }
}

bool ScanPass::has_scans(const std::string& sensor) const {
  return !builders_.at(sensor)->sensors().empty();
}

std::vector<std::string> ScanPass::built() const {
  std::vector<std::string> out;
  for (const auto& [name, builder] : builders_)
    if (!builder->sensors().empty()) out.push_back(name);
  return out;
}

size_t ScanPass::input_points() const {
  size_t points = 0;
  for (const auto& name : built()) points += builders_.at(name)->stats(name).points_in;
  return points;
}

mapping::SensorMapStats ScanPass::sensor_stats(const std::string& sensor) const {
  mapping::SensorMapStats stats = builders_.at(sensor)->stats(sensor);
  if (!merging()) {
    const TiledFilterStats& tiled = tiled_->filter_stats(sensor);
    stats.final_stage.applications = tiled.tiles;
    stats.final_stage.steps = tiled.steps;
  }
  stats.points_out = map_points(sensor);
  return stats;
}

const mapping::SensorMapOptions& ScanPass::sensor_options(const std::string& sensor) const {
  return builder_options_.sensors.at(sensor);
}

}  // namespace keel::pipeline
