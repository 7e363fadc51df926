#include "worker/inspect/inspect_input.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace keel::inspect {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument("inspect input: " + field + " " + problem);
}

std::string at(const std::string& name, size_t i) { return name + "[" + std::to_string(i) + "]"; }

void validate_mesh(const TriangleMesh& mesh) {
  if (mesh.faces.empty()) fail("cad_in_world.faces", "is empty; expected a triangle mesh");
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      fail(at("cad_in_world.vertices", i), "is not finite; expected finite coordinates (m)");
    }
  }
  const int n = static_cast<int>(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if ((mesh.faces[f].array() < 0).any() || (mesh.faces[f].array() >= n).any()) {
      fail(at("cad_in_world.faces", f), "indexes a vertex outside [0, " + std::to_string(n) + ")");
    }
  }
}

void validate_poses(const std::vector<Pose3>& poses) {
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Matrix3d R = poses[i].linear();
    if (!poses[i].matrix().allFinite()) {
      fail(at("T_world_camera", i), "is not finite");
    }
    if (!(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
        !(R.determinant() > 0.0)) {
      fail(at("T_world_camera", i), "is not a rigid transform; expected a rotation matrix");
    }
  }
}

void validate_landmark(const Landmark& l, size_t i, size_t num_views) {
  if (!l.point_world.allFinite()) {
    fail(at("landmarks", i) + ".point_world", "is not finite; expected finite coordinates (m)");
  }
  if (!std::isfinite(l.h_m)) fail(at("landmarks", i) + ".h_m", "is not finite");
  for (size_t k = 0; k < l.views.size(); ++k) {
    const int v = l.views[k];
    const std::string field = at(at("landmarks", i) + ".views", k);
    if (v < 0 || static_cast<size_t>(v) >= num_views) {
      fail(field, "= " + std::to_string(v) + "; expected an index into T_world_camera [0, " +
                      std::to_string(num_views) + ")");
    }
  }
  std::vector<int> sorted = l.views;
  std::sort(sorted.begin(), sorted.end());
  const auto repeated = std::adjacent_find(sorted.begin(), sorted.end());
  if (repeated != sorted.end()) {
    fail(at("landmarks", i) + ".views",
         "lists view " + std::to_string(*repeated) + " twice; expected distinct views");
  }
}

}  // namespace

void validate(const InspectInput& input) {
  validate_mesh(input.cad_in_world);
  validate_poses(input.T_world_camera);
  for (size_t i = 0; i < input.landmarks.size(); ++i) {
    validate_landmark(input.landmarks[i], i, input.T_world_camera.size());
  }
}

}  // namespace keel::inspect
