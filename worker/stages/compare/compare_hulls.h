// Step 3 of the compare stage: hulls (compare_hulls.cc). Both remeshed hulls come from the same
// CAD model, so they are compared in the model frame, each job's products moved back by its own
// x_gM (hull_survey.cc): each vertex of B takes the deviation of A's nearest vertex, and the
// shapes of both shapes.json are matched by overlap into changes.json (new, gone, and the growth
// of each kept shape: compare/shape_matching.h).
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/compare/shape_matching.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

// Writes change_hull.drc / .ply and returns the report section (the changes.json document).
nlohmann::json compare_hulls(StageContext& context, const CompareStageOptions& options,
                             std::vector<std::string>* artifacts);

// True when `dir` holds what a hull comparison reads: mesh_remeshed.drc, shapes.json and
// ba_solution.json.
bool has_hull_products(const std::filesystem::path& dir);

// A hull survey in the model frame, as read from a finished job.
struct HullSurvey {
  std::string job;
  Pose3 T_world_model = Pose3::Identity();
  io::DracoMesh mesh;  // vertices moved into the model frame
  std::vector<float> deviation;
  std::vector<compare::SurveyShape> shapes;
  // Inspect's deviation noise sigma; half of DBSCAN's eps for a footprint radius.
  compare::SurveySigmas sigmas;
};

// Reads mesh_remeshed.drc, shapes.json, ba_solution.json and report.json of `input`; throws
// std::runtime_error naming the job and the file. `fallback_id` names a job without an id.
HullSurvey load_hull_survey(const InputJob& input, const std::string& fallback_id);

}  // namespace keel::pipeline
