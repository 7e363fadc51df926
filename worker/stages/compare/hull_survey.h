// A hull survey as the compare stage reads it from a finished job: its remeshed hull with the
// per-vertex deviation, its shapes and their uncertainties, all moved into the CAD model's
// frame by the job's own x_gM (ba_solution.json), so two surveys of one hull compare there.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/compare/shape_matching.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/pipeline/stage.h"

namespace keel::pipeline {

// True when `dir` holds what a hull comparison reads: mesh_remeshed.drc, shapes.json and
// ba_solution.json.
bool has_hull_products(const std::filesystem::path& dir);

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
