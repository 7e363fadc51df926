#include "worker/stages/ba/artifacts.h"

#include <cmath>

#include "proto/contract_error.h"
#include "worker/pipeline/pose_json.h"

namespace keel::pipeline {

using nlohmann::json;
using proto::ContractError;

json ba_solution_to_json(const BaSolution& s) {
  json cameras = json::array();
  for (size_t i = 0; i < s.T_world_camera.size(); ++i) {
    json c = pose_to_json(s.T_world_camera[i]);
    c["t_ns"] = i < s.t_ns.size() ? s.t_ns[i] : 0;
    cameras.push_back(c);
  }
  json landmarks = json::array();
  for (const auto& l : s.landmarks)
    landmarks.push_back({{"id", l.id},
                         {"p", {l.point_world.x(), l.point_world.y(), l.point_world.z()}},
                         {"h_m", l.h_m},
                         {"lambda", l.lambda},
                         {"views", l.views}});
  return {{"keel_ba_solution", 1},
          {"mode", s.mode},
          {"T_world_model", pose_to_json(s.T_world_model)},
          {"cameras", cameras},
          {"landmarks", landmarks}};
}

BaSolution ba_solution_from_json(const json& document, const std::string& source) {
  proto::FieldReader r(document, source);
  if (r.required<int>("keel_ba_solution") != 1)
    throw ContractError(source + ": keel_ba_solution: expected version 1");
  BaSolution s;
  s.mode = r.required<std::string>("mode");
  s.T_world_model = pose_from_json(r.at("T_world_model"), r.child("T_world_model"));
  const json& cameras = r.at("cameras");
  if (!cameras.is_array()) throw ContractError(source + ".cameras: expected an array");
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string path = source + ".cameras[" + std::to_string(i) + "]";
    s.T_world_camera.push_back(pose_from_json(cameras[i], path));
    s.t_ns.push_back(proto::FieldReader(cameras[i], path).required<int64_t>("t_ns"));
  }
  const json& landmarks = r.at("landmarks");
  if (!landmarks.is_array()) throw ContractError(source + ".landmarks: expected an array");
  for (size_t i = 0; i < landmarks.size(); ++i) {
    const std::string path = source + ".landmarks[" + std::to_string(i) + "]";
    proto::FieldReader lr(landmarks[i], path);
    BaSolutionLandmark l;
    l.id = lr.required<int64_t>("id");
    const auto p = json_numbers<double>(lr.at("p"), lr.child("p"), 3);
    l.point_world = Eigen::Vector3d(p[0], p[1], p[2]);
    l.h_m = lr.required<double>("h_m");
    if (!std::isfinite(l.h_m)) throw ContractError(path + ".h_m: expected a finite number");
    l.lambda = lr.required<int>("lambda");
    l.views = json_numbers<int>(lr.at("views"), lr.child("views"), 0);
    for (int v : l.views)
      if (v < 0 || size_t(v) >= s.T_world_camera.size())
        throw ContractError(path + ".views: index " + std::to_string(v) + " outside the " +
                            std::to_string(s.T_world_camera.size()) + " cameras");
    s.landmarks.push_back(std::move(l));
  }
  return s;
}

}  // namespace keel::pipeline
