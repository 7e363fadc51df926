// Stage `inspect`, as numbered steps:
//   1. options (--set inspect.x=v), ba_solution.json of the `ba` stage and the CAD mesh (the
//      job's CAD blob, else the mission's cad_mesh), moved into the world frame by x_gM;
//   2. run_inspect (Algorithms 1-2 of seed 001);
//   3. artifacts: mesh_remeshed.drc / .ply with the per-vertex deviation, shapes.json;
//   4. report: shapes and heights; with truth.yaml, foreign objects found / missed.
#include "worker/stages/inspect/stage.h"

#include <filesystem>
#include <stdexcept>

#include "worker/inspect/inspect.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/stages/inspect/outputs.h"
#include "worker/stages/inspect/report_json.h"
#include "worker/stages/inspect/solution_input.h"
#include "worker/stages/inspect/truth_objects.h"

namespace keel::pipeline {

StageResult InspectStage::run(StageContext& context) {
  // Step 1.
  const InspectStageOptions options = InspectStageOptions::from_json(context.options);
  const BaSolution solution = read_ba_solution(context.work_dir / kBaSolutionFile);
  const io::Mission mission = load_job_mission(context);
  const std::filesystem::path cad =
      !context.cad_path.empty() ? context.cad_path : mission.cad_mesh_path;
  if (cad.empty())
    throw std::runtime_error(
        "inspect needs a CAD mesh: the job has none and mission.yaml has no cad_mesh");
  const inspect::InspectInput input = inspect_input(solution, io::read_mesh(cad));
  context.progress(0.1);
  context.check_canceled();

  // Step 2.
  const inspect::InspectResult result = inspect::run_inspect(input, options.inspect);
  context.progress(0.8);

  // Step 3.
  const InspectArtifacts artifacts = write_inspect_artifacts(context.work_dir, result, options);

  // Step 4.
  StageResult out;
  out.artifacts = artifacts.files;
  out.report = inspect_report(solution, result, artifacts.draco, options);
  if (!mission.ground_truth_path.empty())
    out.report["truth"] =
        truth_evaluation(mission.ground_truth_path, result.shapes, options.match_distance_m);
  context.progress(1.0);
  return out;
}

std::unique_ptr<Stage> make_inspect_stage() { return std::make_unique<InspectStage>(); }

}  // namespace keel::pipeline
