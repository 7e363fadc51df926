// Stage `calibrate`, as numbered steps (stage.h says what it makes):
//   1. options (`--set calibrate.x=v`, options.h);
//   2. the reference and candidate sensors with this job's extrinsics (sensors.h);
//   3. the body poses as `map` has them (body_poses.h: refine's trajectory correcting the
//      recorded odometry, Algorithm 2) and the keyframes (every keyframe_stride-th);
//   4. per sensor and keyframe, the nearest scan, deskewed, voxel-downsampled
//      (keyframe_scans.h), written as calibration_scans.bin for the calibration page;
//   5. per candidate, the refinement (mapping/extrinsic_refinement.h), and the metrics of
//      Table V of the combined reference + candidate cloud with each extrinsic;
//   6. calibration.json and the report (calibration_json.h; report_html.cc renders it).
#include "worker/stages/calibrate/stage.h"

#include <chrono>
#include <fstream>

#include "core/replaced_file.h"
#include "worker/io/tum.h"
#include "worker/mapping/map_metrics.h"
#include "worker/pipeline/body_poses.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/stages/calibrate/calibration_json.h"
#include "worker/stages/calibrate/keyframe_scans.h"
#include "worker/stages/calibrate/sensors.h"
#include "worker/stages/refine/artifacts.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The keyframes: the refined trajectory's stamps, else the recorded `map`'s, else the poses'.
std::vector<TimeNs> keyframe_stamps(const fs::path& refined, const Poses& poses, int stride) {
  std::error_code ec;
  const Trajectory keyframes = fs::is_regular_file(refined, ec) ? io::read_tum(refined)
                               : !poses.slam_keyframes.empty()  ? poses.slam_keyframes
                                                                : poses.T_world_body;
  std::vector<TimeNs> out;
  for (size_t k = 0; k < keyframes.size(); k += static_cast<size_t>(stride))
    out.push_back(keyframes[k].t_ns);
  return out;
}

std::vector<mapping::PlacedScan> placed(const CalibrationSensorScans& sensor) {
  std::vector<mapping::PlacedScan> out;
  for (const CalibrationScan& scan : sensor.scans) out.push_back({scan.T_world_body, scan.points});
  return out;
}

// The combined cloud of Algorithm 3's window, all keyframes: reference and candidate in world.
PointCloud combined_cloud(const CalibrationSensorScans& reference,
                          const CalibrationSensorScans& candidate,
                          const Pose3& T_reference_candidate) {
  PointCloud cloud;
  cloud.frame = "world";
  for (const CalibrationScan& scan : reference.scans) {
    const Pose3 T = scan.T_world_body * reference.T_body_sensor;
    for (const auto& p : scan.points) cloud.xyz.push_back((T * p.cast<double>()).cast<float>());
  }
  for (const CalibrationScan& scan : candidate.scans) {
    const Pose3 T = scan.T_world_body * reference.T_body_sensor * T_reference_candidate;
    for (const auto& p : scan.points) cloud.xyz.push_back((T * p.cast<double>()).cast<float>());
  }
  return cloud;
}

json metrics_json(const PointCloud& cloud, const CalibrateStageOptions& options,
                  const StageContext& context) {
  mapping::MapMetricsOptions o;
  o.radius_m = options.metrics_radius_m;
  o.threads = options.threads;
  o.max_query_points = options.metrics_max_points;
  o.check_canceled = [&context] { context.check_canceled(); };
  return mapping::to_json(mapping::compute_map_metrics(cloud, o));
}

}  // namespace

StageResult CalibrateStage::run(StageContext& context) {
  const auto start = std::chrono::steady_clock::now();
  json timing = json::object();

  // 1. Options.
  const CalibrateStageOptions options = CalibrateStageOptions::from_json(context.options);

  // 2. The sensors and their extrinsics.
  io::MissionReader reader(load_job_mission(context));
  const CalibrationSelection selection = select_calibration_sensors(reader, options);
  context.check_canceled();
  if (!selection.nothing_to_do.empty()) {
    context.log("calibrate: nothing to calibrate: " + selection.nothing_to_do);
    StageResult out;
    out.report = {{"options", options.to_json()},
                  {"nothing_to_calibrate", selection.nothing_to_do},
                  {"skipped_sensors", selection.skipped}};
    return out;
  }

  // 3. Poses and keyframes.
  const fs::path refined = context.work_dir / kRefinedTrajectoryFile;
  const Poses poses = build_poses(reader, refined, options.odometry_correction, "calibrate");
  const std::vector<TimeNs> keyframes = keyframe_stamps(refined, poses, options.keyframe_stride);

  // 4. The keyframe scans, and the file of the calibration page.
  std::vector<SensorToCollect> sensors;
  for (const CalibrationSensor* s : {&selection.reference})
    sensors.push_back({s->name, s->type, s->T_body_sensor, s->source});
  for (const CalibrationSensor& s : selection.candidates)
    sensors.push_back({s.name, s.type, s.T_body_sensor, s.source});
  KeyframeScanOptions scan_options;
  scan_options.scan_voxel_m = options.scan_voxel_m;
  scan_options.max_sweep_duration_s = options.max_sweep_duration_s;
  const CalibrationScans scans = collect_keyframe_scans(
      reader, keyframes, poses.T_world_body, sensors, selection.reference.name, scan_options,
      [&] { context.check_canceled(); });
  write_calibration_scans(context.work_dir / kCalibrationScansFile, scans);
  timing["scans_s"] = seconds_since(start);
  context.log("calibrate: " + std::to_string(keyframes.size()) + " keyframes, " +
              std::to_string(sensors.size()) + " sensors");
  context.progress(0.3);

  // 5. Each candidate against the reference.
  const CalibrationSensorScans& reference = scans.sensors.front();
  const std::vector<Eigen::Vector3f> reference_points =
      mapping::reference_map_points(placed(reference), selection.reference.T_body_sensor);
  if (reference_points.empty())
    throw std::runtime_error("calibrate: the reference sensor '" + reference.name +
                             "' has no scan at any keyframe");
  mapping::PlaneMapOptions plane_options = options.refinement().planes;
  const mapping::PlaneMap reference_map(reference_points, plane_options);
  timing["reference_map_s"] = seconds_since(start);
  const Pose3 T_reference_body = selection.reference.T_body_sensor.inverse();
  std::vector<CandidateOutcome> outcomes;
  for (size_t k = 0; k < selection.candidates.size(); ++k) {
    context.check_canceled();
    const auto candidate_start = std::chrono::steady_clock::now();
    CandidateOutcome c;
    c.sensor = selection.candidates[k];
    c.T_reference_candidate_initial = T_reference_body * c.sensor.T_body_sensor;
    const CalibrationSensorScans& candidate = scans.sensors[k + 1];
    c.result = mapping::refine_extrinsic(reference_map, placed(candidate),
                                         selection.reference.T_body_sensor,
                                         c.T_reference_candidate_initial, reference.name,
                                         candidate.name, options.refinement(c.sensor.type));
    if (!c.result.refused) {
      c.metrics_before = metrics_json(
          combined_cloud(reference, candidate, c.T_reference_candidate_initial), options, context);
      c.metrics_after = metrics_json(
          combined_cloud(reference, candidate, c.result.T_reference_candidate), options, context);
    }
    c.seconds = seconds_since(candidate_start);
    timing["candidates_s"][c.sensor.name] = c.seconds;
    context.log("calibrate: " + c.sensor.name + " " +
                (c.result.refused ? "refused: " + c.result.reason
                                  : "refined in " + std::to_string(c.seconds) + " s"));
    outcomes.push_back(std::move(c));
    context.progress(0.3 + 0.7 * (k + 1) / selection.candidates.size());
  }

  // 6. calibration.json and the report.
  json calibration = {{"reference", selection.reference.name}, {"candidates", json::array()}};
  for (const CandidateOutcome& c : outcomes)
    calibration["candidates"].push_back(candidate_json(selection.reference, c));
  write_file_replacing(context.work_dir / kCalibrationFile, calibration.dump(2) + "\n");
  StageResult out;
  out.artifacts = {kCalibrationFile, kCalibrationScansFile};
  json& r = out.report;
  r["options"] = options.to_json();
  r["reference"] = {{"sensor", selection.reference.name},
                    {"T_body_sensor", human_pose(selection.reference.T_body_sensor)},
                    {"source", selection.reference.source}};
  r["candidates"] = calibration["candidates"];
  r["skipped_sensors"] = selection.skipped;
  r["poses"] = poses.report;
  r["keyframes"] = keyframes.size();
  timing["total_s"] = seconds_since(start);
  r["timing"] = timing;
  return out;
}

std::unique_ptr<Stage> make_calibrate_stage() { return std::make_unique<CalibrateStage>(); }

}  // namespace keel::pipeline
