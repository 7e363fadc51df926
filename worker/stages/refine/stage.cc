// Stage `refine`, as numbered steps:
//   1. options (--set refine.x=v) and the mission;
//   2. keyframes: the recorded `map` poses (stamps and initial values);
//   3. IMU and DVL samples, extrinsics and noise from mission.yaml (before any scan matching,
//      so a mission without the sensors fails early);
//   4. odometry edges L_ij: the recorded `odometry` interpolated at the keyframes, or GICP
//      between keyframe scans of the first lidar when the mission records none;
//   5. loop closures (loops.csv), and GNSS fixes in the world (ENU) frame when the mission has
//      a gnss sensor (gnss_inputs.cc);
//   6. the batch solve with DVL fusion (seed 000 Sec. IV) and, when ground truth exists, a
//      second solve without it, so the report can set them side by side (Table II);
//   7. trajectory_refined.tum, the self-check against the MAP poses, trajectories.json and the
//      report section (inputs, solver, degeneracy, MAP noise, s_d, the DVL-IMU rotation, DVL
//      gaps, ATE/RPE against ground truth).
#include "worker/stages/refine/stage.h"

#include "worker/io/mission_reader.h"
#include "worker/io/tum.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/pipeline/trajectories_file.h"
#include "worker/stages/refine/dvl_report.h"
#include "worker/stages/refine/evaluation.h"
#include "worker/stages/refine/inputs.h"
#include "worker/stages/refine/report_json.h"
#include "worker/stages/refine/self_check.h"
#include "worker/stages/refine/solves.h"

namespace keel::pipeline {

StageResult RefineStage::run(StageContext& context) {
  // Step 1: options and the mission.
  const RefineStageOptions options = RefineStageOptions::from_json(context.options);
  slam::RefineOptions solver_options = options.solver_options();
  io::MissionReader reader(load_job_mission(context));
  context.check_canceled();

  // Step 2: keyframes.
  Inputs in = recorded_keyframes(reader);
  context.progress(0.05);
  context.check_canceled();

  // Step 3: IMU and DVL.
  inertial_inputs(reader, options, solver_options, in);
  context.progress(0.15);
  context.check_canceled();

  // Step 4: odometry edges.
  odometry_edges(reader, options, solver_options, context, in);
  context.progress(0.3);
  context.check_canceled();

  // Step 5: loop closures.
  loop_closures(reader, options, solver_options, in);
  gnss_inputs(reader, options, in);
  context.log("refine: " + std::to_string(in.solver.keyframes.size()) + " keyframes, " +
              std::to_string(in.solver.odometry.size()) + " odometry edges, " +
              std::to_string(in.solver.loop_closures.size()) + " loop closures, " +
              std::to_string(in.solver.imu.size()) + " IMU and " +
              std::to_string(in.solver.dvl.size()) + " DVL samples");

  // Step 6: the solves.
  const bool has_truth = reader.has_trajectory("ground_truth");
  const Solves solves = solve(in.solver, solver_options, options, has_truth, context);
  const slam::RefineResult& result = solves.written();

  // Step 7: the artifacts and the report.
  const Trajectory& map_poses = in.solver.keyframes;  // the recorded poses of the keyframes
  const Trajectory refined = result.trajectory();
  io::write_tum(context.work_dir / kRefinedTrajectoryFile, refined);
  StageResult out;
  out.artifacts.push_back(kRefinedTrajectoryFile);
  nlohmann::json& r = out.report;
  r["self_check"] = self_check(map_poses, refined, result, context.work_dir / kSelfCheckFile);
  out.artifacts.push_back(kSelfCheckFile);
  r["inputs"] = in.report;
  r["options"] = options.report_json();
  r["solves"] = solves.both()
                    ? "two: with DVL fusion (written to trajectory_refined.tum) and without, "
                      "because ground truth is present (Table II of seed 000)"
                    : (options.dvl ? "one, with DVL fusion" : "one, without DVL fusion");
  r["solver"] = solver_json(result.summary);
  if (solves.both()) r["solver_without_dvl"] = solver_json(solves.without_dvl->summary);
  r["degenerate_keyframes"] = degenerate_json(result);
  r["map_noise"] = map_noise_json(result, options.map_anchors);
  r["dvl"] = solves.with_dvl ? dvl_report_json(*solves.with_dvl, options, reader.mission(), in)
                             : nlohmann::json(nullptr);
  const Trajectory refined_without =
      solves.without_dvl ? solves.without_dvl->trajectory() : Trajectory{};
  const Trajectory truth = has_truth ? reader.read_trajectory("ground_truth") : Trajectory{};
  r["evaluation"] = nullptr;
  if (has_truth) {
    context.check_canceled();
    r["evaluation"] =
        evaluation_json(truth, map_poses, solves.without_dvl ? &refined_without : nullptr,
                        solves.with_dvl ? &refined : nullptr, options, reader.mission());
  }
  write_trajectories(context.work_dir, map_poses, refined,
                     solves.both() ? &refined_without : nullptr, truth, options);
  out.artifacts.push_back(kTrajectoriesFile);
  // Only with GNSS, so that report.json of a mission without it stays what it was.
  if (!in.gnss_sensor.empty()) {
    r["gnss"] = gnss_report_json(result, in, options, reader.manifest());
    r["origin"] = r["gnss"]["origin"];
  }
  r["warnings"] = in.warnings;
  context.progress(1.0);
  return out;
}

std::unique_ptr<Stage> make_refine_stage() { return std::make_unique<RefineStage>(); }

}  // namespace keel::pipeline
