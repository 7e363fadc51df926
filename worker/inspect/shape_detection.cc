#include "worker/inspect/shape_detection.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "worker/inspect/dbscan.h"

namespace keel::inspect {

std::vector<DetectedShape> detect_shapes(int view, const Pose3& T_world_camera,
                                         const std::vector<Landmark>& landmarks,
                                         const std::vector<int>& visible,
                                         const InspectOptions& options) {
  const Pose3 T_camera_world = T_world_camera.inverse();
  std::vector<Eigen::Vector3d> cluster_space;  // P_i: (f_x, f_y, d), line 8
  std::vector<Eigen::Vector3d> points_camera;  // f = H^g_cT l, line 7
  std::vector<int> ids;
  for (const int id : visible) {  // line 4
    const Landmark& landmark = landmarks[id];
    const double d = std::abs(landmark.h_m);  // line 5: d = |h(x_gM, l)|, Eq. (5)
    if (!(d > options.tau_m)) continue;       // line 6
    const Eigen::Vector3d f = T_camera_world * landmark.point_world;  // line 7
    if (f.z() <= 0.0) continue;
    cluster_space.emplace_back(f.x(), f.y(), d);  // line 8
    points_camera.push_back(f);
    ids.push_back(id);
  }
  std::vector<DetectedShape> shapes;
  if (cluster_space.empty()) return shapes;

  const std::vector<int> labels =  // line 11
      dbscan(cluster_space, DbscanOptions{options.dbscan_eps_m, options.dbscan_min_pts});
  const int num = num_clusters(labels);
  std::vector<std::vector<int>> members(num);  // positions in points_camera
  for (size_t k = 0; k < labels.size(); ++k) {
    if (labels[k] != kDbscanNoise) members[labels[k]].push_back(static_cast<int>(k));
  }
  for (const std::vector<int>& cluster : members) {  // lines 12-15
    std::vector<Eigen::Vector3d> cluster_points;
    cluster_points.reserve(cluster.size());
    for (const int k : cluster) cluster_points.push_back(points_camera[k]);
    DetectedShape detected;
    detected.view = view;
    detected.shape = alpha_shape_25d(cluster_points, options.alpha_m);  // line 13
    if (detected.shape.mesh.faces.empty()) continue;
    for (int& source : detected.shape.source_index) source = ids[cluster[source]];
    for (const int k : cluster) detected.landmarks.push_back(ids[k]);
    std::sort(detected.landmarks.begin(), detected.landmarks.end());
    shapes.push_back(std::move(detected));
  }
  return shapes;
}

}  // namespace keel::inspect
