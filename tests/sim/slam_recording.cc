#include "tests/sim/slam_recording.h"

#include <cmath>

#include "tests/sim/inertial_sensors.h"
#include "tests/sim/rng.h"

namespace keel::sim {
namespace {

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

}  // namespace

Trajectory simulate_odometry(const PoseTable& truth, double duration_s, TimeNs t0_ns,
                             const OdometryOptions& o, uint64_t seed) {
  Rng rng(seed, Stream::kOdometry);
  const double scale = 1.0 + o.scale_sigma * rng.gaussian();
  const double yaw_bias = o.yaw_bias_sigma_per_m * rng.gaussian();
  const double gain = o.degenerate_gain + o.degenerate_gain_sigma * rng.gaussian();
  const bool degenerate = o.degenerate_axis_world.norm() > 0.0;
  const Eigen::Vector3d axis =
      degenerate ? o.degenerate_axis_world.normalized() : Eigen::Vector3d::Zero();
  Trajectory out;
  Pose3 previous_true, estimate;
  for (int64_t t_ns : sample_times_ns(o.rate_hz, duration_s)) {
    const Pose3 current_true = truth.T_world_body(t_ns * 1e-9);
    if (out.empty()) {
      estimate = current_true;
    } else {
      // Relative motion in the previous body frame, corrupted, then chained.
      const Pose3 delta = previous_true.inverse() * current_true;
      const double distance = delta.translation().norm();
      Eigen::Vector3d step_world = previous_true.linear() * delta.translation() * scale;
      if (degenerate) step_world += gain * axis.dot(step_world) * axis;
      const double root = std::sqrt(distance);
      step_world += o.translation_walk_per_sqrt_m * root *
                    Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian());
      const double yaw_error = yaw_bias * distance + o.yaw_walk_per_sqrt_m * root * rng.gaussian();
      Pose3 step = Pose3::Identity();
      step.linear() = delta.linear();
      step.translation() = previous_true.linear().transpose() * step_world;
      Pose3 next = estimate * step;
      // Yaw error: rotate the new heading about world z (a gravity-aligned system keeps
      // roll/pitch).
      next.linear() = exp_so3(Eigen::Vector3d(0, 0, yaw_error)) * next.linear();
      estimate = next;
    }
    previous_true = current_true;
    out.push_back({t0_ns + t_ns, estimate});
  }
  return out;
}

Trajectory simulate_map_poses(const PoseTable& truth, double duration_s, TimeNs t0_ns,
                              const MapPoseOptions& o, uint64_t seed) {
  Rng rng(seed, Stream::kMapPoses);
  const bool degenerate = o.degenerate_axis_world.norm() > 0.0;
  const Eigen::Vector3d axis =
      degenerate ? o.degenerate_axis_world.normalized() : Eigen::Vector3d::Zero();
  double axis_error = 0.0;
  Eigen::Vector3d previous_position = Eigen::Vector3d::Zero();
  Trajectory out;
  for (int64_t t_ns : sample_times_ns(o.rate_hz, duration_s)) {
    Pose3 pose = truth.T_world_body(t_ns * 1e-9);
    const Eigen::Vector3d true_position = pose.translation();
    if (!out.empty() && degenerate)
      axis_error += o.degenerate_walk_per_sqrt_m *
                    std::sqrt((true_position - previous_position).norm()) * rng.gaussian();
    previous_position = true_position;
    const Eigen::Vector3d dr(rng.gaussian(), rng.gaussian(), rng.gaussian());
    const Eigen::Vector3d dt(rng.gaussian(), rng.gaussian(), rng.gaussian());
    pose.linear() = pose.linear() * exp_so3(o.sigma_rotation_rad * dr);
    pose.translation() += o.sigma_translation_m * dt + axis_error * axis;
    out.push_back({t0_ns + t_ns, pose});
  }
  return out;
}

double position_rmse(const Trajectory& estimate, const PoseTable& truth, TimeNs t0_ns) {
  double sum = 0.0;
  for (const auto& p : estimate) {
    const Eigen::Vector3d e =
        p.T_world_body.translation() - truth.T_world_body((p.t_ns - t0_ns) * 1e-9).translation();
    sum += e.squaredNorm();
  }
  return estimate.empty() ? 0.0 : std::sqrt(sum / estimate.size());
}

}  // namespace keel::sim
