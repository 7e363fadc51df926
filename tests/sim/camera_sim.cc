#include "tests/sim/camera_sim.h"

#include <algorithm>
#include <cmath>

namespace keel::sim {

bool CameraModel::unproject(double u, double v, Eigen::Vector3d* ray) const {
  const double mx = (u - cx) / fx, my = (v - cy) / fy;
  if (kind == Kind::kPinhole) {
    *ray = Eigen::Vector3d(mx, my, 1.0).normalized();
    return true;
  }
  const double theta_d = std::hypot(mx, my);
  if (theta_d < 1e-12) {
    *ray = Eigen::Vector3d::UnitZ();
    return true;
  }
  // Newton on theta (1 + k1 t^2 + ...) = theta_d.
  double theta = theta_d;
  for (int i = 0; i < 20; ++i) {
    double t2 = theta * theta, poly = 1.0, dpoly = 1.0, power = 1.0;
    for (size_t k = 0; k < distortion.size(); ++k) {
      power *= t2;
      poly += distortion[k] * power;
      dpoly += (2.0 * k + 3.0) * distortion[k] * power;
    }
    const double step = (theta * poly - theta_d) / dpoly;
    theta -= step;
    if (std::abs(step) < 1e-12) break;
  }
  if (theta < 0.0 || theta > max_theta_rad) return false;
  const double s = std::sin(theta) / theta_d;
  *ray = Eigen::Vector3d(mx * s, my * s, std::cos(theta));
  return true;
}

bool CameraModel::project(const Eigen::Vector3d& p, Eigen::Vector2d* uv) const {
  double mx, my;
  if (kind == Kind::kPinhole) {
    if (p.z() <= 1e-9) return false;
    mx = p.x() / p.z(), my = p.y() / p.z();
  } else {
    const double r = std::hypot(p.x(), p.y());
    const double theta = std::atan2(r, p.z());
    if (theta > max_theta_rad) return false;
    double t2 = theta * theta, poly = 1.0, power = 1.0;
    for (double k : distortion) power *= t2, poly += k * power;
    const double theta_d = theta * poly;
    mx = r > 1e-12 ? theta_d * p.x() / r : 0.0;
    my = r > 1e-12 ? theta_d * p.y() / r : 0.0;
  }
  *uv = Eigen::Vector2d(fx * mx + cx, fy * my + cy);
  return uv->x() >= 0.0 && uv->y() >= 0.0 && uv->x() <= width - 1.0 && uv->y() <= height - 1.0;
}

cv::Mat render_image(const SimWorld& world, const CameraModel& camera, const Pose3& T_world_camera,
                     const CameraRenderOptions& options, Rng& rng) {
  cv::Mat image(camera.height, camera.width, CV_8UC1);
  const Eigen::Matrix3d R = T_world_camera.linear();
  const Eigen::Vector3d origin = T_world_camera.translation();
  for (int v = 0; v < camera.height; ++v) {
    uint8_t* row = image.ptr<uint8_t>(v);
    for (int u = 0; u < camera.width; ++u) {
      Eigen::Vector3d ray;
      const double noise = options.intensity_sigma * rng.gaussian();
      if (!camera.unproject(u, v, &ray)) {
        row[u] = 0;
        continue;
      }
      const Eigen::Vector3d dir = R * ray;
      RayHit hit;
      const bool found = world.raycast(origin, dir, 0.01, options.max_range_m, &hit);
      const double value = world.shade(origin, dir, found ? &hit : nullptr) + noise;
      row[u] = static_cast<uint8_t>(std::clamp(std::lround(255.0 * value), 0L, 255L));
    }
  }
  return image;
}

std::vector<TrackObservation> visible_landmarks(const SimWorld& world, const CameraModel& camera,
                                                const Pose3& T_world_camera,
                                                const std::vector<Landmark>& landmarks,
                                                double max_range_m) {
  std::vector<TrackObservation> out;
  const Pose3 T_camera_world = T_world_camera.inverse();
  const Eigen::Vector3d center = T_world_camera.translation();
  for (const auto& lm : landmarks) {
    const Eigen::Vector3d to_camera = center - lm.p_world;
    const double range = to_camera.norm();
    if (range > max_range_m || lm.normal_world.dot(to_camera) <= 0.0) continue;
    Eigen::Vector2d uv;
    if (!camera.project(T_camera_world * lm.p_world, &uv)) continue;
    if (uv.x() < 2.0 || uv.y() < 2.0 || uv.x() > camera.width - 3.0 || uv.y() > camera.height - 3.0)
      continue;
    RayHit hit;
    const Eigen::Vector3d dir = -to_camera / range;
    if (world.raycast(center, dir, 0.01, range - 0.005, &hit)) continue;  // occluded
    out.push_back({lm.id, uv.x(), uv.y()});
  }
  return out;
}

}  // namespace keel::sim
