#include "worker/stages/map/map_draco.h"

#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/map/artifacts.h"
#include "worker/stages/map/metrics.h"
#include "worker/stages/map/output_runner.h"
#include "worker/stages/map/tiled_outputs.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Writes map_<name>.drc of a map of `points` points, whose encoding took `earlier_seconds`
// and then ran from `start`; report {"points", "draco": {...}, "sidecar"}.
MapOutput write_map_draco(const io::DracoEncoded& encoded, size_t points, Clock::time_point start,
                          double earlier_seconds, const std::string& name,
                          const MapStageOptions& options, const fs::path& work_dir) {
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

// map_<name>_preview.drc of a map larger than preview_max_points, from its gathered parts.
MapOutput write_preview(const std::vector<const PointCloud*>& parts,
                        const io::PartsAttributes& attributes, const std::string& name,
                        const MapStageOptions& options, const fs::path& work_dir) {
  return preview_output(write_map_preview(parts, attributes, options.preview_max_points,
                                          draco_options(options), map_preview_file(name),
                                          work_dir));
}

// A sensor map gathered from its tiles.
PointCloud gather(TiledMaps& tiled, const std::string& name) {
  const std::vector<std::string> parts = {name};
  return gather_tiled_map(tiled, parts, tiled.output_partition(parts));
}

}  // namespace

io::DracoOptions draco_options(const MapStageOptions& options) {
  io::DracoOptions draco;
  draco.position_bits = options.draco_position_bits;
  draco.compression_level = options.draco_compression_level;
  return draco;
}

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

void write_sensor_draco(TiledMaps& tiled, const std::string& name, size_t points,
                        const MapStageOptions& options, const fs::path& work_dir,
                        const std::function<void()>& check_canceled, MapOutput& draco,
                        MapOutput& preview) {
  const auto start = Clock::now();
  const PointCloud map = gather(tiled, name);
  io::PartsAttributes attributes;
  if (options.write_point_metrics)
    add_point_metric_fields(map.xyz, map_metrics_options(options, check_canceled), attributes);
  draco = write_map_draco(io::encode_draco_point_cloud({&map}, draco_options(options), attributes),
                          points, start, 0.0, name, options, work_dir);
  if (wants_preview(points, options.preview_max_points))
    preview = write_preview({&map}, attributes, name, options, work_dir);
}

CombinedDraco::CombinedDraco(TiledMaps& tiled, std::vector<std::string> parts, size_t points,
                             const MapStageOptions& options, fs::path work_dir)
    : tiled_(tiled),
      options_(options),
      work_dir_(std::move(work_dir)),
      points_(points),
      parts_(std::move(parts)),
      attributes_{kSensorAttribute, parts_, {}, {}} {}

std::vector<const PointCloud*> CombinedDraco::part_pointers() const {
  std::vector<const PointCloud*> out;
  for (const auto& map : maps_) out.push_back(&map);
  return out;
}

void CombinedDraco::encode(const std::function<void()>& check_canceled, MapOutput& preview) {
  const auto start = Clock::now();
  for (const auto& name : parts_) maps_.push_back(gather(tiled_, name));
  const std::vector<const PointCloud*> parts = part_pointers();
  if (options_.write_point_metrics) {
    std::vector<Eigen::Vector3f> positions;
    positions.reserve(points_);
    for (const PointCloud* part : parts)
      positions.insert(positions.end(), part->xyz.begin(), part->xyz.end());
    add_point_metric_fields(positions, map_metrics_options(options_, check_canceled), attributes_);
  }
  encoded_ = io::encode_draco_point_cloud_bytes(parts, draco_options(options_), attributes_);
  if (wants_preview(points_, options_.preview_max_points))
    preview = write_preview(parts, attributes_, kCombinedMapName, options_, work_dir_);
  encode_seconds_ = seconds_since(start);
}

void CombinedDraco::check(MapOutput& draco) {
  const auto start = Clock::now();
  io::measure_draco_point_cloud(part_pointers(), draco_options(options_), &encoded_);
  draco = write_map_draco(encoded_, points_, start, encode_seconds_, kCombinedMapName, options_,
                          work_dir_);
  encoded_ = io::DracoEncoded{};
  maps_.clear();
  maps_.shrink_to_fit();
}

}  // namespace keel::pipeline
