#include "worker/pipeline/servo_tray.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace keel::pipeline {
namespace {

// Largest distance of the DVL origin from the tray's axis that counts as on it, m.
constexpr double kOnAxisM = 1e-3;

}  // namespace

Eigen::Vector3d tray_axis(const proto::SensorSpec& servo) {
  const auto axis = servo.axis.value_or(std::array<double, 3>{0, 0, 1});
  return Eigen::Vector3d(axis[0], axis[1], axis[2]).normalized();
}

std::optional<double> servo_angle_at(const io::ServoSeries& servo, TimeNs t_ns,
                                     TimeNs half_window_ns) {
  if (servo.empty() || t_ns < servo.front().t_ns || t_ns > servo.back().t_ns) return std::nullopt;
  auto lo = std::lower_bound(servo.begin(), servo.end(), t_ns - half_window_ns,
                             [](const io::ServoSample& x, TimeNs t) { return x.t_ns < t; });
  double n = 0, st = 0, sa = 0, stt = 0, sta = 0;
  for (auto it = lo; it != servo.end() && it->t_ns <= t_ns + half_window_ns; ++it) {
    const double dt = 1e-9 * double(it->t_ns - t_ns);
    n += 1, st += dt, sa += it->angle_rad, stt += dt * dt, sta += dt * it->angle_rad;
  }
  const double det = n * stt - st * st;
  if (n < 3 || det <= 0)
    return io::interpolate_series(servo, t_ns,
                                  [](const io::ServoSample& x) { return x.angle_rad; });
  return (stt * sa - st * sta) / det;  // intercept of the fit at t_ns
}

TrayDvlStats rotate_tray_dvl(std::vector<slam::DvlSample>& samples, const io::ServoSeries& servo,
                             const Pose3& T_body_servo, const Eigen::Vector3d& axis_servo,
                             const Pose3& T_body_dvl0, TimeNs half_window_ns) {
  if (!(axis_servo.norm() > 0) || !axis_servo.allFinite())
    throw std::invalid_argument("servo tray: the axis must be a finite, non-zero vector");
  const Eigen::Vector3d axis = (T_body_servo.linear() * axis_servo).normalized();
  const Eigen::Vector3d from_pivot = T_body_dvl0.translation() - T_body_servo.translation();
  const double off_axis_m = (from_pivot - axis * axis.dot(from_pivot)).norm();
  if (off_axis_m > kOnAxisM)
    throw std::invalid_argument(
        "servo tray: the DVL origin is " + std::to_string(off_axis_m) +
        " m off the tray's axis; the velocity the turning tray adds there is not modelled "
        "(put T_body_sensor's origin on the axis through the servo's origin)");
  const Eigen::Matrix3d R_body_dvl0 = T_body_dvl0.linear();
  TrayDvlStats stats;
  for (slam::DvlSample& s : samples) {
    if (!s.valid) continue;
    const std::optional<double> angle = servo_angle_at(servo, s.t_ns, half_window_ns);
    if (!angle) {
      s.valid = false;
      ++stats.without_angle;
      continue;
    }
    const Eigen::Matrix3d R_body_dvl =
        Eigen::AngleAxisd(*angle, axis).toRotationMatrix() * R_body_dvl0;
    s.velocity_mps = R_body_dvl0.transpose() * (R_body_dvl * s.velocity_mps);
    ++stats.rotated;
    stats.max_angle_rad = std::max(stats.max_angle_rad, std::abs(*angle));
  }
  return stats;
}

}  // namespace keel::pipeline
