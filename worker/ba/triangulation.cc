#include "worker/ba/triangulation.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace keel::ba {
namespace {

struct View {
  Pose3 T_camera_world;
  const PinholeCamera* camera;
  Eigen::Vector2d pixel;
};

std::vector<View> views_of(const FeatureTrack& track, const std::vector<Pose3>& T_world_camera,
                           const BaRig& rig) {
  std::vector<View> views;
  for (const FeatureObservation& obs : track.observations) {
    const Pose3& T_world_top = T_world_camera.at(obs.keyframe);
    views.push_back({T_world_top.inverse(), &rig.camera_top, obs.pixel});
    if (obs.pixel_bottom && rig.camera_bottom) {
      views.push_back(
          {(T_world_top * rig.T_top_bottom).inverse(), &*rig.camera_bottom, *obs.pixel_bottom});
    }
  }
  return views;
}

// DLT: each view gives x (P3 . X) - (P1 . X) = 0 and y (P3 . X) - (P2 . X) = 0 with P = [R|t]
// and (x, y) the normalised coordinates; X is the right singular vector of the least
// singular value.
std::optional<Eigen::Vector3d> linear_triangulation(const std::vector<View>& views) {
  Eigen::MatrixXd A(2 * views.size(), 4);
  for (size_t i = 0; i < views.size(); ++i) {
    const PinholeCamera& c = *views[i].camera;
    const double x = (views[i].pixel.x() - c.cx) / c.fx;
    const double y = (views[i].pixel.y() - c.cy) / c.fy;
    const Eigen::Matrix<double, 3, 4> P = views[i].T_camera_world.matrix().topRows<3>();
    A.row(2 * i) = x * P.row(2) - P.row(0);
    A.row(2 * i + 1) = y * P.row(2) - P.row(1);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X[3]) < 1e-12) return std::nullopt;  // point at infinity
  return Eigen::Vector3d(X.head<3>() / X[3]);
}

double max_parallax_rad(const std::vector<View>& views, const Eigen::Vector3d& point) {
  double best = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const Eigen::Vector3d ri =
        (point - views[i].T_camera_world.inverse().translation()).normalized();
    for (size_t j = i + 1; j < views.size(); ++j) {
      const Eigen::Vector3d rj =
          (point - views[j].T_camera_world.inverse().translation()).normalized();
      best = std::max(best, std::acos(std::clamp(ri.dot(rj), -1.0, 1.0)));
    }
  }
  return best;
}

bool within_gates(const std::vector<View>& views, const Eigen::Vector3d& point,
                  double max_reprojection_px, const TriangulationOptions& options) {
  if (!point.allFinite()) return false;
  for (const View& v : views) {
    const Eigen::Vector3d p_c = v.T_camera_world * point;
    if (p_c.z() < options.min_depth_m || p_c.norm() > options.max_depth_m) return false;
    const Eigen::Vector2d uv(v.camera->fx * p_c.x() / p_c.z() + v.camera->cx,
                             v.camera->fy * p_c.y() / p_c.z() + v.camera->cy);
    if ((uv - v.pixel).norm() > max_reprojection_px) return false;
  }
  return true;
}

}  // namespace

bool landmark_within_gates(const Eigen::Vector3d& point, const FeatureTrack& track,
                           const std::vector<Pose3>& T_world_camera, const BaRig& rig,
                           double max_reprojection_px, const TriangulationOptions& options) {
  return within_gates(views_of(track, T_world_camera, rig), point, max_reprojection_px, options);
}

std::optional<Eigen::Vector3d> triangulate_track(const FeatureTrack& track,
                                                 const std::vector<Pose3>& T_world_camera,
                                                 const BaRig& rig,
                                                 const TriangulationOptions& options) {
  const std::vector<View> views = views_of(track, T_world_camera, rig);
  if (views.size() < 2) return std::nullopt;
  const std::optional<Eigen::Vector3d> point = linear_triangulation(views);
  if (!point || !within_gates(views, *point, options.max_reprojection_px, options))
    return std::nullopt;
  const bool has_stereo = std::any_of(track.observations.begin(), track.observations.end(),
                                      [](const FeatureObservation& o) { return o.pixel_bottom; });
  if (!has_stereo && max_parallax_rad(views, *point) < options.min_parallax_deg * kDegToRad) {
    return std::nullopt;
  }
  return point;
}

}  // namespace keel::ba
