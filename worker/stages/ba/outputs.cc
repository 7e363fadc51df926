#include "worker/stages/ba/outputs.h"

#include "worker/io/draco/draco_codec.h"
#include "worker/io/text_writer.h"
#include "worker/io/tum.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/trajectories_file.h"
#include "worker/stages/ba/artifacts.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

BaSolution solution_of(const ba::BaModeResult& m, const std::vector<ba::BaKeyframe>& keyframes) {
  BaSolution s;
  s.mode = ba::to_string(m.mode);
  s.T_world_model = m.T_world_model;
  for (const auto& k : keyframes) s.t_ns.push_back(k.t_ns);
  s.T_world_camera = m.T_world_camera;
  for (const auto& l : m.landmarks) {
    const ba::InspectionPoint at = ba::inspection_point(l);
    s.landmarks.push_back({l.id, at.position_world, at.signed_distance_m, l.lambda, l.keyframes});
  }
  return s;
}

// Fig. 18(a)-(b) as a table: state (gicp | ba), keyframe time, hit point in the CAD frame,
// measured minus predicted range.
void write_dvl_residuals(const fs::path& path, const ba::BaModeResult& m,
                         const std::vector<ba::BaKeyframe>& keyframes) {
  io::TextWriter w(path);
  w.text("state,t,x_model_m,y_model_m,z_model_m,residual_m\n");
  for (const auto& [state, beams] :
       {std::pair{"gicp", &m.dvl_residuals_initial}, std::pair{"ba", &m.dvl_residuals_final}}) {
    for (const ba::DvlBeamResidual& b : *beams) {
      w.text(state).text(",").seconds(keyframes[b.keyframe].t_ns);
      for (double x : {b.hit_model.x(), b.hit_model.y(), b.hit_model.z(), b.residual_m})
        w.text(",").number(x);
      w.text("\n");
    }
  }
  w.close();
}

// trajectories.json's `ba`: the keyframe poses in the CAD model frame (x_gM^-1 T_world_vehicle),
// where the hull products of ba are; T_world_model places them in the world.
void write_model_frame_trajectory(const fs::path& work_dir, const ba::BaModeResult& m,
                                  const std::vector<ba::BaKeyframe>& keyframes) {
  const Pose3 T_model_world = m.T_world_model.inverse();
  Trajectory in_model;
  for (size_t i = 0; i < keyframes.size(); ++i)
    in_model.push_back({keyframes[i].t_ns, T_model_world * m.T_world_vehicle[i]});
  add_to_trajectories_file(work_dir, {{"ba", "model", in_model, {}}}, m.T_world_model);
}

// cad_model.drc (the job's CAD mesh as given, model frame) and its sidecar; report figures.
json write_cad_model(const fs::path& work_dir, const TriangleMesh& cad,
                     const BaStageOptions& options) {
  io::DracoOptions draco;
  draco.position_bits = options.cad_draco_position_bits;
  const io::DracoEncoded encoded = io::encode_draco_mesh(cad, {}, draco);
  io::write_draco_file(work_dir / kCadModelFile, encoded.bytes);
  return {{"file", kCadModelFile},
          {"bytes", encoded.bytes.size()},
          {"max_position_error_m", encoded.max_position_error_m},
          {"position_error_bound_m", encoded.position_error_bound_m},
          {"sidecar", write_draco_sidecar(work_dir, kCadModelFile, encoded.summary, "model")}};
}

}  // namespace

const ba::BaModeResult& artifact_mode(const ba::BaResult& result) {
  const ba::BaModeResult* proposed = result.find(ba::BaMode::kProposed);
  return proposed ? *proposed : result.modes.back();
}

BaArtifacts write_ba_artifacts(const fs::path& work_dir, const ba::BaModeResult& mode,
                               const ba::BaProblem& problem, const BaStageOptions& options) {
  Trajectory refined;
  for (size_t i = 0; i < problem.keyframes.size(); ++i)
    refined.push_back({problem.keyframes[i].t_ns, mode.T_world_vehicle[i]});
  io::write_tum(work_dir / kBaTrajectoryFile, refined);
  write_json_atomically(
      work_dir / kBaSolutionFile,
      nlohmann::ordered_json(ba_solution_to_json(solution_of(mode, problem.keyframes))));
  write_dvl_residuals(work_dir / kBaDvlResidualsFile, mode, problem.keyframes);
  write_model_frame_trajectory(work_dir, mode, problem.keyframes);
  BaArtifacts out;
  out.cad_model = write_cad_model(work_dir, problem.cad_mesh, options);
  out.files = {kBaTrajectoryFile, kBaSolutionFile, kBaDvlResidualsFile,
               kTrajectoriesFile, kCadModelFile,   out.cad_model["sidecar"].get<std::string>()};
  return out;
}

}  // namespace keel::pipeline
