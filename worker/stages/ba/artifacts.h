// What the `ba` stage writes that other stages read: the file names, and ba_solution.json's
// codec (the `inspect` stage reads the landmarks and x_gM; `compare` the model frame).
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/time.h"

namespace keel::pipeline {

inline constexpr const char* kBaTrajectoryFile = "trajectory_ba.tum";
inline constexpr const char* kBaSolutionFile = "ba_solution.json";
// Fig. 18(a)-(b): each DVL beam's residual where it meets the CAD mesh, after GICP and after the
// BA (the artifacts' mode): `state,t,x_model_m,y_model_m,z_model_m,residual_m`.
inline constexpr const char* kBaDvlResidualsFile = "dvl_residuals.csv";
// The job's CAD mesh as a Draco mesh in its own (model) frame, for measuring against it in a
// viewer; its sidecar is cad_model.json.
inline constexpr const char* kCadModelFile = "cad_model.drc";

// ba_solution.json <-> its contents (also what the inspect stage reads).
struct BaSolutionLandmark {
  int64_t id = 0;
  Eigen::Vector3d point_world = Eigen::Vector3d::Zero();
  double h_m = 0.0;        // Eq. (5) signed distance to the CAD mesh, positive outside
  int lambda = 0;          // Eq. (7) label, 1 = on the model
  std::vector<int> views;  // indices into BaSolution::T_world_camera
};
struct BaSolution {
  std::string mode;
  Pose3 T_world_model = Pose3::Identity();  // x_gM
  std::vector<TimeNs> t_ns;                 // per keyframe
  std::vector<Pose3> T_world_camera;        // per keyframe, top camera
  std::vector<BaSolutionLandmark> landmarks;
};
nlohmann::json ba_solution_to_json(const BaSolution& solution);
// Throws ContractError naming `source` and the field.
BaSolution ba_solution_from_json(const nlohmann::json& document, const std::string& source);

}  // namespace keel::pipeline
