// Stage `map`, as numbered steps (stage.h says what it makes; each step's file, what it does):
//   1. options (`--set map.x=v`, options.h);
//   2. the scan sensors to map (sensors.h);
//   3. poses (Sec. VI-C, worker/pipeline/body_poses.h), and on them the TF tree, a MapBuilder per
//   sensor, the
//      SLAM-map baseline and the maps' tiles (scan_pass.h);
//   4. every scan of every sensor through its MapBuilder, then the sensor's final filters over
//      its tiles (scan_pass.h);
//   5. outputs: each sensor map's and the combined map's (Eq. (21)) Draco, PLY and LOD tile
//      files, as output tasks (output_plan.h): a sensor's start on one extra thread once its
//      map is complete, while the next sensors scan, the rest costliest first on `threads`
//      threads within the memory budget;
//   6. the metrics of Table V (Eqs. (23)-(26)) of the SLAM map, the SLAM lidar's inspection
//      map and the combined map, measured by output tasks too (metrics.h);
//   7. the report: poses, sensors and their filters, files, metrics, timing, memory and
//      warnings (report_json.h; report_html.cc renders it), and with mission.yaml's `origin`,
//      the origin in the report and every sidecar (origin_sidecars.h).
// docs/map-filters.md explains the throughput and memory choices.
#include "worker/stages/map/stage.h"

#include <chrono>
#include <string>
#include <vector>

#include "worker/io/mission_reader.h"
#include "worker/pipeline/body_poses.h"
#include "worker/stages/map/metrics.h"
#include "worker/stages/map/origin_sidecars.h"
#include "worker/stages/map/output_plan.h"
#include "worker/stages/map/output_runner.h"
#include "worker/stages/map/report_json.h"
#include "worker/stages/map/scan_pass.h"
#include "worker/stages/map/sensors.h"
#include "worker/stages/refine/artifacts.h"

namespace keel::pipeline {

using nlohmann::json;

StageResult MapStage::run(StageContext& context) {
  MapTimes times;
  times.stage_start = std::chrono::steady_clock::now();
  reset_peak_rss();

  // 1. Options.
  const MapStageOptions options = MapStageOptions::from_json(context.options);

  // 2. The sensors to map.
  io::MissionReader reader(io::load_mission(context.mission_dir));
  const SensorSelection selection = select_sensors(reader, options);
  context.check_canceled();

  // 3. Poses, and the mapping on them.
  const Poses poses = build_poses(reader, context.work_dir / kRefinedTrajectoryFile,
                                  options.odometry_correction, "map");
  ScanPass scans(options, selection, poses, context.work_dir);

  // 4. Every scan of every sensor. The outputs of a sensor whose map is complete start at once
  //    (step 5) but for the last sensor's, and none with a single thread.
  const size_t total_scans = scans.open_scans(reader);
  context.log("map: " + std::to_string(total_scans) + " scans of " +
              std::to_string(selection.mapped.size()) + " sensors, " +
              std::to_string(poses.T_world_body.size()) + " poses");
  const auto scans_start = std::chrono::steady_clock::now();
  json warnings = json::array();
  // Declared after `scans`, whose maps its tasks read; on a failure it removes their files.
  OutputPlan outputs(options, scans, context, warnings, scans_start);
  const bool early_outputs = options.threads >= 2;
  if (early_outputs) outputs.run_beside_scans();
  const size_t sensors = selection.mapped.size();
  for (size_t k = 0; k < sensors; ++k) {
    scans.scan_sensor(k, context);
    outputs.rethrow_if_failed();  // an earlier sensor's output failed: stop scanning
    scans.finish_sensor(k, context);
    if (early_outputs && k + 1 < sensors) outputs.start_sensor(selection.mapped[k].name);
  }
  context.check_canceled();
  times.scans_seconds = seconds_since(scans_start);
  times.input_points = scans.input_points();
  context.log("map: " + std::to_string(times.input_points) + " points in " +
              std::to_string(times.scans_seconds) + " s");

  // 5. Outputs: the tasks not started yet and the combined map's.
  StageResult out;
  json& r = out.report;
  r["options"] = options.to_json();
  r["poses"] = poses.report;
  r["skipped_sensors"] = selection.skipped;
  times.outputs_start = std::chrono::steady_clock::now();
  const double outputs_cpu_start = process_cpu_seconds();
  r["sensors"] = describe_sensors(selection, scans, warnings);
  const std::vector<std::string> written = written_sensor_maps(selection, scans);
  r["slam_map"] = describe_slam_map(scans, options, warnings);
  outputs.run_rest();
  outputs.collect(written, out);

  // 6. Table V.
  r["metrics"] =
      metrics_report(outputs.metrics(), inspection_map_name(scans.slam_sensor(), written), options,
                     times.metrics_seconds, times.metrics_query_points);

  // 7. The rest of the report.
  r["timing"] = timing_report(times, options.threads);
  r["memory"] = memory_report(options, scans.tiled(), outputs.budget_bytes());
  r["warnings"] = warnings;
  if (reader.manifest().origin) {
    r["origin"] = origin_json(*reader.manifest().origin);
    add_origin_to_sidecars(context.work_dir, out.artifacts, reader.manifest().origin);
  }
  outputs.keep();
  context.log("map: outputs and metrics " + std::to_string(seconds_since(times.outputs_start)) +
              " s wall, " + std::to_string(process_cpu_seconds() - outputs_cpu_start) + " s cpu");
  context.progress(1.0);
  return out;
}

std::unique_ptr<Stage> make_map_stage() { return std::make_unique<MapStage>(); }

}  // namespace keel::pipeline
