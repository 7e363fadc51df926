#include "worker/stages/compare/compare_hulls.h"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include "worker/pipeline/report.h"
#include "worker/stages/ba/artifacts.h"
#include "worker/stages/inspect/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json read_json(const fs::path& path, const std::string& job) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("job " + job + ": no " + path.filename().string());
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw std::runtime_error("job " + job + ": " + path.filename().string() +
                             ": not valid JSON: " + e.what());
  }
}

Eigen::Vector3d json_vector(const json& v, const std::string& what) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    throw std::runtime_error(what + ": expected 3 numbers");
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

void read_mesh(const InputJob& input, HullSurvey* s) {
  const Pose3 T_model_world = s->T_world_model.inverse();
  try {
    s->mesh = io::decode_draco_mesh(io::read_draco_file(input.dir / kRemeshedDracoFile),
                                    kRemeshedDracoFile);
  } catch (const std::exception& e) {
    throw std::runtime_error("job " + s->job + ": " + e.what());
  }
  for (auto& v : s->mesh.mesh.vertices) v = T_model_world * v;
  for (const auto& f : s->mesh.fields)
    if (f.name == "deviation") s->deviation = f.values;
  if (s->deviation.size() != s->mesh.mesh.vertices.size())
    throw std::runtime_error("job " + s->job + ": " + kRemeshedDracoFile +
                             " has no per-vertex `deviation`");
}

void read_shapes(const InputJob& input, HullSurvey* s) {
  const Pose3 T_model_world = s->T_world_model.inverse();
  const json shapes = read_json(input.dir / kShapesFile, s->job);
  const std::string where = "job " + s->job + ": " + kShapesFile;
  if (!shapes.contains("shapes") || !shapes["shapes"].is_array())
    throw std::runtime_error(where + ": expected a `shapes` list");
  const double eps =
      shapes.contains("options") ? shapes["options"].value("dbscan_eps_m", 0.0) : 0.0;
  s->sigmas.radius_m = 0.5 * eps;
  for (size_t i = 0; i < shapes["shapes"].size(); ++i) {
    const json& j = shapes["shapes"][i];
    const std::string at = where + ": shapes[" + std::to_string(i) + "]";
    compare::SurveyShape shape;
    shape.id = j.value("id", int(i));
    shape.centroid_model =
        T_model_world * json_vector(j.at("centroid_world_m"), at + ".centroid_world_m");
    shape.height_m = j.value("max_deviation_m", 0.0);
    shape.height_sampling_sigma_m = j.value("height_sampling_sigma_m", 0.0);
    // The footprint from the world bounding box: a disc of radius R tilted anywhere spans
    // 2R sqrt(1 - n_i^2) along axis i, so the two largest spans average 1.6R-2R.
    Eigen::Vector3d extent = json_vector(j.at("extent_m"), at + ".extent_m");
    std::sort(extent.data(), extent.data() + 3);
    shape.radius_m = 0.25 * (extent[1] + extent[2]);
    s->shapes.push_back(shape);
  }
}

}  // namespace

bool has_hull_products(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / kRemeshedDracoFile, ec) &&
         fs::is_regular_file(dir / kShapesFile, ec) &&
         fs::is_regular_file(dir / kBaSolutionFile, ec);
}

HullSurvey load_hull_survey(const InputJob& input, const std::string& fallback_id) {
  HullSurvey s;
  s.job = input.job.value("id", fallback_id);
  const BaSolution solution =
      ba_solution_from_json(read_json(input.dir / kBaSolutionFile, s.job), kBaSolutionFile);
  s.T_world_model = solution.T_world_model;
  read_mesh(input, &s);
  read_shapes(input, &s);
  const json report = read_json(input.dir / kReportFileName, s.job);
  if (report.contains("stages") && report["stages"].contains("inspect"))
    s.sigmas.height_m = report["stages"]["inspect"].value("deviation_noise_sigma_m", 0.0);
  return s;
}

}  // namespace keel::pipeline
