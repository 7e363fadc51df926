#include "worker/stages/map/map_outputs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/map/artifacts.h"
#include "worker/stages/map/tiled_outputs.h"

namespace keel::pipeline {

namespace fs = std::filesystem;

// Finest LOD tiles hold at most this many points (1.6 MB .pnts files).
constexpr size_t kLodMaxPointsPerTile = 100000;

void merge_output(MapOutput& into, const MapOutput& part) {
  into.report.update(part.report);
  into.artifacts.insert(into.artifacts.end(), part.artifacts.begin(), part.artifacts.end());
}

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

std::string map_preview_file(const std::string& sensor) { return "map_" + sensor + "_preview.drc"; }

bool wants_preview(size_t points, size_t max_points) {
  return max_points > 0 && points > max_points;
}

std::vector<size_t> even_thinning(size_t n, size_t m) {
  std::vector<size_t> out;
  out.reserve(std::min(n, m));
  if (m >= n) {
    for (size_t i = 0; i < n; ++i) out.push_back(i);
    return out;
  }
  // Algorithm S: keep index i with probability (still to keep) / (still to see).
  uint64_t state = 0x9e3779b97f4a7c15ULL ^ (n * 0xbf58476d1ce4e5b9ULL) ^ m;
  auto uniform = [&state] {  // splitmix64, 53 bits into [0, 1)
    uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  };
  for (size_t i = 0; i < n && out.size() < m; ++i)
    if (static_cast<double>(n - i) * uniform() < static_cast<double>(m - out.size()))
      out.push_back(i);
  return out;
}

PointMetricFields point_metric_fields(const std::vector<Eigen::Vector3f>& xyz,
                                      mapping::MapMetricsOptions options) {
  options.max_query_points = 0;  // every point
  mapping::PointMetrics metrics = mapping::compute_point_metrics(xyz, options);
  PointMetricFields out;
  out.fields = {{"density", std::move(metrics.surface_density)},
                {"roughness", std::move(metrics.roughness)},
                {"planarity", std::move(metrics.planarity)}};
  for (auto& field : out.fields) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float v : field.values)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!(lo <= hi)) lo = hi = 0.0f;  // nothing defined
    const float span = std::max(hi - lo, std::max(std::fabs(lo), 1.0f) * 1e-6f);
    const float no_data = lo - span / 1024.0f;
    for (float& v : field.values)
      if (!std::isfinite(v)) v = no_data;
    out.no_data.push_back(no_data);
  }
  return out;
}

void add_point_metric_fields(const std::vector<Eigen::Vector3f>& xyz,
                             const mapping::MapMetricsOptions& options,
                             io::PartsAttributes& attributes) {
  PointMetricFields fields = point_metric_fields(xyz, options);
  attributes.fields = std::move(fields.fields);
  attributes.fields_no_data = std::move(fields.no_data);
}

nlohmann::json preview_entry(const std::string& sensor, size_t points, size_t max_points) {
  if (!wants_preview(points, max_points)) return nullptr;
  return {{"file", map_preview_file(sensor)}, {"points", max_points}};
}

MapOutput preview_output(PreviewOutput preview) {
  return {{{"preview", std::move(preview.report)}}, std::move(preview.artifacts)};
}

PreviewOutput write_map_preview(const std::vector<const PointCloud*>& parts,
                                const io::PartsAttributes& attributes, size_t max_points,
                                const io::DracoOptions& draco, const std::string& file,
                                const fs::path& work_dir) {
  size_t n = 0;
  for (const PointCloud* part : parts) n += part->size();
  if (n <= max_points)
    throw std::invalid_argument("write_map_preview: a map of " + std::to_string(n) +
                                " points needs no preview of " + std::to_string(max_points));
  const std::vector<size_t> kept = even_thinning(n, max_points);
  // The kept points of each part, and the fields' values at them (in the same order).
  std::vector<PointCloud> thinned(parts.size());
  io::PartsAttributes thinned_attributes{
      attributes.label_name, attributes.part_labels, {}, attributes.fields_no_data};
  for (const auto& field : attributes.fields) thinned_attributes.fields.push_back({field.name, {}});
  size_t k = 0, part_start = 0;
  for (size_t p = 0; p < parts.size(); ++p) {
    const PointCloud& part = *parts[p];
    const size_t part_end = part_start + part.size();
    for (; k < kept.size() && kept[k] < part_end; ++k) {
      const size_t i = kept[k] - part_start;
      thinned[p].xyz.push_back(part.xyz[i]);
      if (part.has_intensity()) thinned[p].intensity.push_back(part.intensity[i]);
      for (size_t f = 0; f < attributes.fields.size(); ++f)
        thinned_attributes.fields[f].values.push_back(attributes.fields[f].values[kept[k]]);
    }
    part_start = part_end;
  }
  std::vector<const PointCloud*> thinned_parts;
  for (const auto& part : thinned) thinned_parts.push_back(&part);
  const io::DracoEncoded encoded =
      io::encode_draco_point_cloud(thinned_parts, draco, thinned_attributes);
  io::write_draco_file(work_dir / file, encoded.bytes);
  PreviewOutput out;
  out.artifacts = {file, write_draco_sidecar(work_dir, file, encoded.summary, "world")};
  out.report = {{"file", file},
                {"points", max_points},
                {"bytes", encoded.bytes.size()},
                {"sidecar", out.artifacts[1]}};
  return out;
}

}  // namespace keel::pipeline
