#include "worker/stages/inspect/solution_input.h"

#include <fstream>
#include <stdexcept>
#include <string>

namespace keel::pipeline {

BaSolution read_ba_solution(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error("inspect needs " + path.filename().string() +
                             " of a `ba` stage: cannot open " + path.string());
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(path.string() + ": not valid JSON: " + e.what());
  }
  return ba_solution_from_json(document, path.filename().string());
}

inspect::InspectInput inspect_input(const BaSolution& solution, TriangleMesh cad_in_model) {
  inspect::InspectInput input;
  input.cad_in_world = std::move(cad_in_model);
  for (auto& v : input.cad_in_world.vertices) v = solution.T_world_model * v;
  for (auto& n : input.cad_in_world.vertex_normals) n = solution.T_world_model.linear() * n;
  input.T_world_camera = solution.T_world_camera;
  for (const auto& l : solution.landmarks)
    input.landmarks.push_back({l.point_world, l.h_m, l.lambda, l.views});
  return input;
}

}  // namespace keel::pipeline
