// Stage `ba`, as numbered steps:
//   1. options (--set ba.x=v), the sensors (camera, dvl_ranges, servo, depth) and their rig;
//   2. keyframes at the camera's images: initial poses, odometry, servo angle, depth, images;
//   3. feature tracks (the SIFT frontend inside the BA, or the mission's ground-truth tracks);
//   4. DVL range returns at the keyframes, and the CAD mesh;
//   5. run_model_assisted_ba for the chosen modes;
//   6. artifacts of one mode and the report of every mode (x_gM against truth when given).
#include "worker/stages/ba/stage.h"

#include <filesystem>
#include <stdexcept>

#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/stages/ba/dvl_returns.h"
#include "worker/stages/ba/ground_truth_tracks.h"
#include "worker/stages/ba/keyframes.h"
#include "worker/stages/ba/outputs.h"
#include "worker/stages/ba/sensors.h"

namespace keel::pipeline {

StageResult BaStage::run(StageContext& context) {
  // Step 1.
  const BaStageOptions options = BaStageOptions::from_json(context.options);
  const io::Mission mission = load_job_mission(context);
  io::MissionReader reader(mission);
  const BaSensors sensors = pick_sensors(reader, options);
  ba::BaProblem problem;
  problem.rig = build_rig(reader, sensors);

  // Step 2: images are decoded only for the frontend.
  const bool frontend = options.tracks == "frontend";
  BaKeyframes keyframes = build_keyframes(reader, sensors, options, frontend, context);
  problem.keyframes = std::move(keyframes.keyframes);
  problem.odometry = std::move(keyframes.odometry);

  // Step 3.
  if (!frontend)
    problem.tracks = ground_truth_tracks(mission, sensors.camera->name, problem.keyframes);

  // Step 4.
  problem.dvl_ranges =
      dvl_ranges_at_keyframes(reader, *sensors.dvl, problem.keyframes, options.dvl_max_dt_s);
  const std::filesystem::path cad =
      !context.cad_path.empty() ? context.cad_path : mission.cad_mesh_path;
  if (cad.empty())
    throw std::runtime_error(
        "ba needs a CAD mesh: the job has none and mission.yaml has no cad_mesh");
  problem.cad_mesh = io::read_mesh(cad);
  context.progress(0.1);
  context.check_canceled();
  context.log("ba: " + std::to_string(problem.keyframes.size()) + " keyframes, " +
              (frontend ? std::string("frontend tracks")
                        : std::to_string(problem.tracks.size()) + " ground-truth tracks") +
              ", " + std::to_string(problem.dvl_ranges.size()) + " DVL returns");

  // Step 5.
  const ba::BaResult result = ba::run_model_assisted_ba(problem, options.solver_options());
  context.progress(0.9);

  // Step 6.
  const ba::BaModeResult& chosen = artifact_mode(result);
  const BaArtifacts artifacts = write_ba_artifacts(context.work_dir, chosen, problem, options);
  StageResult out;
  out.artifacts = artifacts.files;
  out.report = ba_report(input_report(keyframes, sensors, frontend, cad), result, chosen,
                         artifacts.cad_model, truth_T_world_cad(mission), options);
  context.progress(1.0);
  return out;
}

std::unique_ptr<Stage> make_ba_stage() { return std::make_unique<BaStage>(); }

}  // namespace keel::pipeline
