#include "tests/sim/range_sensors.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace keel::sim {
namespace {

float intensity_of(const RayHit& hit, const Eigen::Vector3d& dir) {
  const double cosine = std::abs(hit.normal.dot(dir));
  return static_cast<float>(std::clamp(255.0 * hit.albedo * (0.2 + 0.8 * cosine), 0.0, 255.0));
}

}  // namespace

PointCloud simulate_lidar_sweep(const SimWorld& world, const PoseTable& poses,
                                const Pose3& T_body_sensor, double t_start_s,
                                const SpinningLidarOptions& o, Rng& rng) {
  std::vector<double> sin_el(o.rings), cos_el(o.rings);
  for (int r = 0; r < o.rings; ++r) {
    const double el = (o.elevation_min_deg +
                       (o.elevation_max_deg - o.elevation_min_deg) * r / std::max(o.rings - 1, 1)) *
                      M_PI / 180.0;
    sin_el[r] = std::sin(el);
    cos_el[r] = std::cos(el);
  }
  PointCloud cloud;
  cloud.reserve(o.rings * o.points_per_ring);
  const double column_dt = 1.0 / (o.points_per_ring * o.rate_hz);
  for (int j = 0; j < o.points_per_ring; ++j) {
    const double offset_s = j * column_dt;
    const Pose3 T_world_sensor = poses.T_world_body(t_start_s + offset_s) * T_body_sensor;
    const Eigen::Matrix3d R = T_world_sensor.linear();
    const Eigen::Vector3d origin = T_world_sensor.translation();
    const double azimuth = 2.0 * M_PI * j / o.points_per_ring;
    const double ca = std::cos(azimuth), sa = std::sin(azimuth);
    for (int r = 0; r < o.rings; ++r) {
      const Eigen::Vector3d dir_sensor(cos_el[r] * ca, cos_el[r] * sa, sin_el[r]);
      const Eigen::Vector3d dir = R * dir_sensor;
      RayHit hit;
      const double noise = o.range_sigma_m * rng.gaussian();  // drawn for every ray: stable streams
      if (!world.raycast(origin, dir, o.range_min_m, o.range_max_m, &hit) || !hit.returns) continue;
      const double range = hit.range_m + noise;
      if (range < o.range_min_m || range > o.range_max_m) continue;
      cloud.xyz.push_back((dir_sensor * range).cast<float>());
      cloud.intensity.push_back(intensity_of(hit, dir));
      cloud.ring.push_back(static_cast<uint16_t>(r));
      cloud.time_s.push_back(static_cast<float>(offset_s));
    }
  }
  return cloud;
}

PointCloud simulate_sonar_ping(const SimWorld& world, const Pose3& T_world_sensor,
                               const ProfilingSonarOptions& o, Rng& rng) {
  PointCloud cloud;
  const Eigen::Matrix3d R = T_world_sensor.linear();
  const Eigen::Vector3d origin = T_world_sensor.translation();
  for (int b = 0; b < o.beams; ++b) {
    const double angle =
        (-0.5 * o.fan_deg + o.fan_deg * b / std::max(o.beams - 1, 1)) * M_PI / 180.0;
    const Eigen::Vector3d dir_sensor(std::cos(angle), 0.0, std::sin(angle));
    const Eigen::Vector3d dir = R * dir_sensor;
    RayHit hit;
    const double noise = o.range_sigma_m * rng.gaussian();
    if (!world.raycast(origin, dir, o.range_min_m, o.range_max_m, &hit) || !hit.returns) continue;
    const double range = hit.range_m + noise;
    if (range < o.range_min_m || range > o.range_max_m) continue;
    cloud.xyz.push_back((dir_sensor * range).cast<float>());
    cloud.intensity.push_back(intensity_of(hit, dir));
  }
  return cloud;
}

}  // namespace keel::sim
