#include "worker/stages/map/options.h"

#include <cmath>
#include <stdexcept>

#include "worker/mapping/map_metrics.h"
#include "worker/mapping/voxel_accumulator.h"
#include "worker/stages/map/stage.h"
#include "worker/stages/map/tiled_maps.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;
using Options = MapStageOptions;
using Row = OptionRow<Options>;

// A row's docs: unit, meaning, source, group, and the default's text when not the struct's.
OptionDoc doc(const char* unit, std::string meaning, const char* source, const char* group,
              const char* default_text = "") {
  return {unit, std::move(meaning), source, group, default_text};
}

// "expected <words>" unless `ok(value)`: the map stage's messages say what the value means.
template <typename T>
Check<T> expect(bool (*ok)(const T&), std::string words) {
  return [ok, words](const T& v) { return ok(v) ? std::string() : "expected " + words; };
}

const char* const kChainObject =
    "an object {scan_filters, intermediary_filters, final_filters, deskew}";

// A filter-chain object (docs/map-filters.md), checked as a whole by the table's Validate.
Row chains_row(const char* name, json Options::*field, const std::string& expected, OptionDoc doc) {
  Row row = option(name, field, expect<json>([](const json& v) { return v.is_object(); }, expected),
                   std::move(doc));
  row.type = "object";
  return row;
}

// `--set map.sensors=lidar_h` arrives as a string; `["lidar_h","sonar"]` as an array.
Row sensors_row(OptionDoc doc) {
  Row row{"sensors", "array of strings", std::move(doc), {}, {}};
  row.read = [](Options& o, const json& value, const std::string& path) {
    o.sensors = value.is_string()
                    ? std::vector<std::string>{value.get<std::string>()}
                    : proto::FieldReader::convert<std::vector<std::string>>(value, path);
  };
  row.write = [](const Options& o) { return json(o.sensors); };
  return row;
}

// A count of points: read as a signed integer so that a negative one is refused, not wrapped.
Row points_row(const char* name, size_t Options::*field, bool (*ok)(const long long&),
               const char* expected, OptionDoc doc) {
  Row row{name, "integer", std::move(doc), {}, {}};
  row.read = [field, ok, expected](Options& o, const json& value, const std::string& path) {
    const auto points = proto::FieldReader::convert<long long>(value, path);
    require(ok(points), path, expected);
    o.*field = static_cast<size_t>(points);
  };
  row.write = [field](const Options& o) { return json(o.*field); };
  return row;
}

// Without LOD tiles a big map gets a preview by default; read before preview_max_points, which
// then overrides it.
Row write_tiles_row(OptionDoc doc) {
  Row row = option("write_tiles", &Options::write_tiles, std::move(doc));
  row.read = [](Options& o, const json& value, const std::string& path) {
    o.write_tiles = proto::FieldReader::convert<bool>(value, path);
    if (!o.write_tiles) o.preview_max_points = Options::kDefaultPreviewPoints;
  };
  return row;
}

// The filter chains fail here, naming the option path, rather than halfway through a job.
void validate_chains(const Options& o, const std::string&) {
  try {
    o.sensor_options("", "lidar");
    o.sensor_options("", "sonar");
    for (const auto& item : o.sensor_filters.items()) {
      o.sensor_options(item.key(), "lidar");
      o.sensor_options(item.key(), "sonar");
    }
  } catch (const std::invalid_argument& e) {
    throw proto::ContractError(e.what());
  }
}

const char* const kSensors = "**Sensors and filters** (MapBuilder, seed 000 Fig. 5)";
const char* const kPoses = "**Poses** (seed 000 Sec. VI-C)";
const char* const kFiles = "**Files** (docs/artifacts.md)";
const char* const kMetrics = "**Metrics** (seed 000 Table V, Eqs. (23)-(26))";
const char* const kResources = "**Threads and memory**";

}  // namespace

const OptionTable<MapStageOptions>& map_option_table() {
  static const OptionTable<Options> table(
      "map",
      {
          sensors_row(doc("",
                          "names of the scan sensors to map. Sensors with `mounted_on` (servo "
                          "trays) are skipped and listed in the report: their extrinsic varies "
                          "with the tray angle, and MapBuilder's TF tree holds static extrinsics",
                          "seed 000 Sec. VI", kSensors, "every lidar and sonar")),
          chains_row("lidar_filters", &Options::lidar_filters, kChainObject,
                     doc("",
                         "per-sensor options ([map-filters.md](map-filters.md#per-sensor-options-"
                         "of-the-map-stage)) for every `lidar`; keys given replace the defaults",
                         "seed 000 Table IV (the default scan filters)", kSensors)),
          chains_row("sonar_filters", &Options::sonar_filters, kChainObject,
                     doc("", "the same for every `sonar`", "seed 000 Table IV", kSensors)),
          chains_row(
              "sensor_filters", &Options::sensor_filters,
              "an object {\"<sensor>\": {scan_filters, intermediary_filters, "
              "final_filters, deskew}}",
              doc("", "`{\"<sensor>\": {...}}`, applied after the type's options", "", kSensors)),
          option("final_voxel_leaf_m", &Options::final_voxel_leaf_m,
                 expect<double>([](const double& v) { return std::isfinite(v) && v >= 0.0; },
                                "a leaf in metres >= 0 (0: no final voxel grid)"),
                 doc("m",
                     "leaf of the final voxel grid added to every default chain; 0 = none (Table "
                     "IV exactly; the map then holds every filtered point)",
                     "beyond the paper: memory follows the surveyed structure", kSensors)),
          option("final_voxel_merge_radius_leaves", &Options::final_voxel_merge_radius_leaves,
                 expect<double>(
                     [](const double& v) {
                       return v >= 0.0 && v <= mapping::VoxelAccumulator::kMaxMergeLeaves;
                     },
                     "a radius in leaves in [0, 2] (0: no merging)"),
                 doc("leaves",
                     "merge radius, in leaves (at most 2), of every streamed final voxel grid: a "
                     "point landing in an empty voxel joins the occupied neighbour whose centroid "
                     "is nearest and within the radius ([map-filters.md](map-filters.md#merge-"
                     "rule-final_voxel_merge_radius_leaves)); 0 = plain voxel grid",
                     "beyond the paper", kSensors)),
          option("scans_per_intermediary", &Options::scans_per_intermediary,
                 int_in_range(1, 100000), doc("scans", "N_I", "seed 000 Eq. (22)", kSensors)),
          option("deskew", &Options::deskew,
                 doc("", "default of every sensor's `deskew`", "seed 000 Sec. VI", kSensors)),
          option("max_sweep_duration_s", &Options::max_sweep_duration_s,
                 expect<double>([](const double& v) { return v > 0.0; }, "> 0"),
                 doc("s", "per-point time spans above this are refused (a unit mistake)",
                     "beyond the paper", kSensors)),
          option("odometry_correction", &Options::odometry_correction,
                 doc("", "correct the recorded `odometry` by the keyframe poses",
                     "seed 000 Algorithm 2", kPoses)),
          option("draco_position_bits", &Options::draco_position_bits, int_in_range(1, 30),
                 doc("bits",
                     "Draco position quantization: error <= sqrt(3)/2 * extent / (2^18 - 1), "
                     "0.66 mm on a 200 m map",
                     "beyond the paper", kFiles)),
          option("draco_compression_level", &Options::draco_compression_level, int_in_range(0, 10),
                 doc("",
                     "0 (fast) .. 10 (small); Draco codes the kd-tree's bits directly at 0-1 and "
                     "through rANS from 2; 0 is Draco's sequential encoding, which keeps the "
                     "points' order. Why 1: [map-filters.md](map-filters.md#throughput-and-memory-"
                     "issue-5-targets)",
                     "beyond the paper", kFiles)),
          option("write_ply", &Options::write_ply,
                 doc("", "also write `map_<sensor>.ply`", "", kFiles)),
          option(
              "write_point_metrics", &Options::write_point_metrics,
              doc("",
                  "also store density, roughness and planarity (Eqs. 23-26, every point a query "
                  "point, neighbours within `metrics_radius_m` in the same map) as the Draco "
                  "attributes `density`, `roughness`, `planarity` of every map and preview, for "
                  "a viewer to colour by (docs/artifacts.md, \"Draco sidecar\"). Off by default: "
                  "every point costs ~4 µs of CPU (~1600 neighbours within 0.25 m on a 2 cm "
                  "map), 3 s per million points on the keel-sim bridge, against the 20000 "
                  "sampled query points of Table V",
                  "beyond the paper", kFiles)),
          option("metrics_radius_m", &Options::metrics_radius_m,
                 expect<double>(
                     [](const double& v) {
                       return std::isfinite(v) && v > 0.0 && v <= mapping::kMaxMetricsRadiusM;
                     },
                     "a radius in metres in (0, " + std::to_string(mapping::kMaxMetricsRadiusM) +
                         "] (Table V: 0.25)"),
                 doc("m",
                     "r of Eqs. (23)-(26), at most 1 m (a wider neighbourhood measures shape, not "
                     "surface, at r² the cost)",
                     "seed 000 Table V", kMetrics)),
          points_row(
              "metrics_max_points", &Options::metrics_max_points,
              [](const long long& n) { return n >= 0; }, "an integer >= 0 (0: every point)",
              doc("points",
                  "query points per map, evenly strided (neighbours come from the whole "
                  "map); 0 = every point. The report gives distributions, which 20000 "
                  "samples estimate to within ~0.7 % of a standard deviation (standard error "
                  "std / sqrt(20000)) at a fraction of the cost of every point of a 2 cm map "
                  "(~1600 neighbours each within 0.25 m)",
                  "beyond the paper", kMetrics)),
          option("slam_sensor", &Options::slam_sensor,
                 doc("", "the lidar whose keyframe scans make the SLAM-map baseline",
                     "seed 000 Table V", kMetrics, "first lidar")),
          option("slam_keyframe_leaf_m", &Options::slam_keyframe_leaf_m,
                 expect<double>([](const double& v) { return std::isfinite(v) && v > 0.0; },
                                "a leaf in metres > 0"),
                 doc("m", "voxel leaf of each SLAM keyframe scan (LIO-SAM-like)",
                     "beyond the paper", kMetrics)),
          option("threads", &Options::threads, int_in_range(1, 256),
                 doc("", "threads of the scans and of the output tasks", "", kResources)),
          option("memory_budget_mb", &Options::memory_budget_mb,
                 expect<int>([](const int& v) { return v >= kMinMemoryBudgetMb && v <= 1 << 20; },
                             "an integer in [" + std::to_string(kMinMemoryBudgetMb) +
                                 ", 1048576] (MiB; the spill buffers and a tile per thread need at "
                                 "least " +
                                 std::to_string(kMinMemoryBudgetMb) + ")"),
                 doc("MiB",
                     "the memory the stage keeps its maps within (at least 64): see "
                     "[map-filters.md](map-filters.md#maps-out-of-core-issue-17), \"Maps out of "
                     "core\". A budget too small for one tile fails the job naming the smallest "
                     "that would work",
                     "beyond the paper", kResources)),
          write_tiles_row(
              doc("",
                  "also write each map as level-of-detail tiles, `tiles_<map>.tar` (OGC "
                  "3D Tiles, docs/artifacts.md)",
                  "", kFiles)),
          points_row(
              "preview_max_points", &Options::preview_max_points,
              [](const long long& n) { return n == 0 || (n >= 1000 && n <= 1000000000LL); },
              "0 (none) or an integer in [1000, 1e9]",
              doc("points",
                  "a map with more points also gets `map_<sensor>_preview.drc` (and its "
                  "sidecar): a uniform random subset of exactly this many points with the "
                  "same attributes, which a viewer opens first; 0 (none) or an integer in "
                  "[1000, 1e9]. With level-of-detail tiles (the default) the viewer opens a "
                  "big map from its coarsest tiles, so no preview is made unless asked for: "
                  "on the 220 s bridge the previews took 4.9 of the stage's 13.2 output "
                  "seconds",
                  "beyond the paper", kFiles, "0 (none) with `write_tiles`, else 2000000")),
      },
      validate_chains);
  return table;
}

MapStageOptions MapStageOptions::from_json(const json& options) {
  return map_option_table().from_json(options);
}

json MapStageOptions::to_json() const { return map_option_table().to_json(*this); }

mapping::SensorMapOptions MapStageOptions::sensor_options(const std::string& sensor,
                                                          const std::string& type) const {
  const bool sonar = type == "sonar";
  mapping::SensorMapOptions defaults;
  defaults.scan_filters =
      sonar ? mapping::table_iv_sonar_scan_filters() : mapping::table_iv_lidar_scan_filters();
  if (final_voxel_leaf_m > 0.0)
    defaults.final_filters.filters.push_back(mapping::VoxelGridFilter{final_voxel_leaf_m});
  defaults.deskew = deskew;
  defaults = mapping::sensor_map_options_from_json(
      sonar ? sonar_filters : lidar_filters,
      sonar ? "options.map.sonar_filters" : "options.map.lidar_filters", defaults);
  if (!sensor.empty() && sensor_filters.contains(sensor))
    defaults = mapping::sensor_map_options_from_json(
        sensor_filters.at(sensor), "options.map.sensor_filters." + sensor, defaults);
  return defaults;
}

void throw_memory_budget_error(const TileBudgetError& error, const MapStageOptions& options) {
  const double minimum_mb =
      std::ceil(error.minimum_bytes() * options.threads / kTileShare / (1 << 20));
  throw proto::ContractError(
      "options.map.memory_budget_mb: " + std::to_string(options.memory_budget_mb) +
      " MiB cannot hold one tile (" + error.what() + "); the smallest budget that would work is " +
      std::to_string(static_cast<long long>(minimum_mb)) + " MiB");
}

const OptionsSchema& MapStage::options() const { return map_option_table(); }

}  // namespace keel::pipeline
