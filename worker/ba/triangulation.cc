#include "worker/ba/triangulation.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace keel::ba {
namespace {

struct View {
  Pose3 T_camera_world;
  const PinholeCamera* camera;
  Eigen::Vector2d pixel;
};

// The top camera's view of `obs` and, for a stereo observation, the bottom camera's.
void append_views(const FeatureObservation& obs, const std::vector<Pose3>& T_world_camera,
                  const BaRig& rig, std::vector<View>* views) {
  const Pose3& T_world_top = T_world_camera.at(obs.keyframe);
  views->push_back({T_world_top.inverse(), &rig.camera_top, obs.pixel});
  if (obs.pixel_bottom && rig.camera_bottom) {
    views->push_back(
        {(T_world_top * rig.T_top_bottom).inverse(), &*rig.camera_bottom, *obs.pixel_bottom});
  }
}

std::vector<View> views_of(const FeatureTrack& track, const std::vector<Pose3>& T_world_camera,
                           const BaRig& rig) {
  std::vector<View> views;
  for (const FeatureObservation& obs : track.observations)
    append_views(obs, T_world_camera, rig, &views);
  return views;
}

double reprojection_error_px(const View& v, const Eigen::Vector3d& point) {
  const Eigen::Vector3d p_c = v.T_camera_world * point;
  if (!(p_c.z() > 0)) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d uv(v.camera->fx * p_c.x() / p_c.z() + v.camera->cx,
                           v.camera->fy * p_c.y() / p_c.z() + v.camera->cy);
  return (uv - v.pixel).norm();
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
    if (reprojection_error_px(v, point) > max_reprojection_px) return false;
  }
  return true;
}

}  // namespace

std::vector<double> observation_reprojection_errors_px(const Eigen::Vector3d& point,
                                                       const FeatureTrack& track,
                                                       const std::vector<Pose3>& T_world_camera,
                                                       const BaRig& rig) {
  std::vector<double> errors;
  std::vector<View> views;
  for (const FeatureObservation& obs : track.observations) {
    views.clear();
    append_views(obs, T_world_camera, rig, &views);
    double worst = 0;
    for (const View& v : views) worst = std::max(worst, reprojection_error_px(v, point));
    errors.push_back(worst);
  }
  return errors;
}

bool landmark_within_gates(const Eigen::Vector3d& point, const FeatureTrack& track,
                           const std::vector<Pose3>& T_world_camera, const BaRig& rig,
                           double max_reprojection_px, const TriangulationOptions& options) {
  return within_gates(views_of(track, T_world_camera, rig), point, max_reprojection_px, options);
}

double robust_pixel_sigma_px(const std::vector<Eigen::Vector3d>& points,
                             const std::vector<FeatureTrack>& tracks,
                             const std::vector<Pose3>& T_world_camera, const BaRig& rig) {
  if (points.size() != tracks.size())
    throw std::invalid_argument("robust_pixel_sigma_px: " + std::to_string(points.size()) +
                                " points for " + std::to_string(tracks.size()) + " tracks");
  std::vector<double> scaled;
  for (size_t k = 0; k < tracks.size(); ++k) {
    const std::vector<View> views = views_of(tracks[k], T_world_camera, rig);
    const size_t m = 2 * views.size();
    if (m <= 3) continue;
    const double dof_scale = std::sqrt(double(m) / double(m - 3));
    // One error per image (a stereo observation's two cameras apart): the larger of two
    // Rayleigh errors would put the median at 1.57 sigma, not 1.18.
    for (const View& v : views) {
      const double e = reprojection_error_px(v, points[k]);
      if (std::isfinite(e)) scaled.push_back(dof_scale * e);
    }
  }
  if (scaled.empty()) return std::numeric_limits<double>::infinity();
  std::nth_element(scaled.begin(), scaled.begin() + scaled.size() / 2, scaled.end());
  return scaled[scaled.size() / 2] / std::sqrt(2.0 * std::log(2.0));
}

bool gate_landmark_observations(const Eigen::Vector3d& point, FeatureTrack& track,
                                const std::vector<Pose3>& T_world_camera, const BaRig& rig,
                                double gate_px, const TriangulationOptions& options) {
  const std::vector<double> errors =
      observation_reprojection_errors_px(point, track, T_world_camera, rig);
  std::vector<FeatureObservation> consistent;
  for (size_t o = 0; o < errors.size(); ++o)
    if (errors[o] <= gate_px) consistent.push_back(track.observations[o]);
  track.observations = std::move(consistent);
  const bool stereo = std::any_of(track.observations.begin(), track.observations.end(),
                                  [](const FeatureObservation& o) { return o.pixel_bottom; });
  const size_t min_views = stereo ? 2 : static_cast<size_t>(options.min_monocular_views);
  return track.observations.size() >= min_views &&
         landmark_within_gates(point, track, T_world_camera, rig, gate_px, options);
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
