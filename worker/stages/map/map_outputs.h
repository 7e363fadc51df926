// The map stage's files of one map (docs/artifacts.md) and their report entries: the PLY file
// and the LOD tiles, made from its tiles; the preview, an even thinning of a large map that a
// viewer opens first; and the per-point metrics (Eqs. 23-26 of seed 000) as named Draco
// attributes. The single Draco file is map_draco.h's.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/mapping/map_metrics.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {

// The combined map's label attribute: each point's sensor (its index in the labels).
inline constexpr const char* kSensorAttribute = "sensor";

// One map's artifacts and their figures for the report (a part of report.json's map entry).
struct MapOutput {
  nlohmann::json report = nlohmann::json::object();
  std::vector<std::string> artifacts;
};
// `part`'s report keys and artifacts, added to `into`.
void merge_output(MapOutput& into, const MapOutput& part);

// Writes map_<name>.ply, the map made of `parts` (TiledMaps' maps), tile by tile; report
// {"ply": {...}}.
MapOutput write_tiled_map_ply(TiledMaps& tiled, const std::vector<std::string>& parts,
                              const std::string& name, const std::filesystem::path& work_dir,
                              const std::function<void()>& check_canceled);
// Writes tiles_<name>.tar, the LOD tileset of the map made of `parts`; report {"tiles": {...}}.
MapOutput write_map_tiles(TiledMaps& tiled, const std::vector<std::string>& parts,
                          const std::string& name, const std::filesystem::path& work_dir,
                          const std::function<void()>& check_canceled);

// `map_<sensor>_preview.drc`.
std::string map_preview_file(const std::string& sensor);
// Whether a map of `points` points gets a preview of `max_points` (0: none).
bool wants_preview(size_t points, size_t max_points);

// The indices kept by an even thinning of n points to m < n, ascending: exactly m of them, each
// index kept with the same probability m / n (Knuth's selection sampling, Algorithm S, with a
// fixed seed: the same n and m give the same indices). A uniform draw rather than every (n/m)-th
// point: map points come in a structured order (grid rows), and a fixed stride over them
// samples the same rows of every column, leaving stripes. m >= n keeps every index.
std::vector<size_t> even_thinning(size_t n, size_t m);

// Eqs. (23)-(26) at every point, with neighbours from `xyz` (mapping::compute_point_metrics with
// every point a query point): fields "density" (points/m^2), "roughness" (m) and "planarity",
// with each field's no_data where the metric is undefined (roughness with fewer than 3 other
// neighbours, planarity of a degenerate neighbourhood): just below the field's smallest defined
// value (by 1/1024 of its span), so it is the quantized attribute's minimum, which Draco returns
// exactly, and the quantization steps of the defined values barely grow.
struct PointMetricFields {
  std::vector<io::ScalarField> fields;
  std::vector<float> no_data;  // one per field
};
PointMetricFields point_metric_fields(const std::vector<Eigen::Vector3f>& xyz,
                                      mapping::MapMetricsOptions options);
// The same as the Draco fields of `attributes`.
void add_point_metric_fields(const std::vector<Eigen::Vector3f>& xyz,
                             const mapping::MapMetricsOptions& options,
                             io::PartsAttributes& attributes);

struct PreviewOutput {
  nlohmann::json report = nlohmann::json::object();  // {"file", "points", "bytes", "sidecar"}
  std::vector<std::string> artifacts;                // the preview and its sidecar
};

// Writes `file` (Draco) with the even thinning to `max_points` of the map given as `parts`
// (concatenated in order), with the same attributes (`attributes`: the parts' label, and fields
// over the whole map, thinned alike), and its sidecar. Only for a map larger than max_points.
PreviewOutput write_map_preview(const std::vector<const PointCloud*>& parts,
                                const io::PartsAttributes& attributes, size_t max_points,
                                const io::DracoOptions& draco, const std::string& file,
                                const std::filesystem::path& work_dir);

// The sidecar's "preview" entry of a map of `points` points: {"file", "points"}, or null when
// the map needs none (points <= max_points).
nlohmann::json preview_entry(const std::string& sensor, size_t points, size_t max_points);
// A preview as a map output: report {"preview": {...}}.
MapOutput preview_output(PreviewOutput preview);

}  // namespace keel::pipeline
