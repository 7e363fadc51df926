#include "worker/slam/relative_pose.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {

Matrix6d isotropic_information(double sigma_translation_m, double sigma_rotation_rad) {
  Matrix6d info = Matrix6d::Zero();
  info.diagonal().head<3>().setConstant(1.0 / (sigma_translation_m * sigma_translation_m));
  info.diagonal().tail<3>().setConstant(1.0 / (sigma_rotation_rad * sigma_rotation_rad));
  return info;
}

Matrix6d OdometryNoise::information(const Pose3& T_i_j) const {
  const double dist = T_i_j.translation().norm();
  const double angle = so3_log(T_i_j.linear()).norm();
  return isotropic_information(
      sigma_translation_m + sigma_translation_per_m * dist,
      sigma_rotation_rad + sigma_rotation_per_rad * angle + sigma_rotation_per_m * dist);
}

Pose3 interpolate_pose(const Trajectory& trajectory, TimeNs t_ns) {
  if (trajectory.empty() || t_ns < trajectory.front().t_ns || t_ns > trajectory.back().t_ns) {
    throw std::out_of_range("time " + format_seconds(t_ns) +
                            " s is outside the trajectory's time span");
  }
  auto it = std::lower_bound(trajectory.begin(), trajectory.end(), t_ns,
                             [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
  if (it->t_ns == t_ns) return it->T_world_body;
  const StampedPose& b = *it;
  const StampedPose& a = *(it - 1);
  const double alpha = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  const Eigen::Quaterniond qa(a.T_world_body.linear());
  const Eigen::Quaterniond qb(b.T_world_body.linear());
  return make_pose(qa.slerp(alpha, qb), (1.0 - alpha) * a.T_world_body.translation() +
                                            alpha * b.T_world_body.translation());
}

std::vector<RelativePoseMeasurement> relative_poses_from_trajectory(
    const Trajectory& odometry, const std::vector<TimeNs>& keyframe_t_ns,
    const OdometryNoise& noise, const std::vector<Matrix6d>& information) {
  for (size_t k = 1; k < odometry.size(); ++k) {
    if (odometry[k].t_ns <= odometry[k - 1].t_ns) {
      throw std::invalid_argument("odometry pose " + std::to_string(k) +
                                  ": timestamp not after the previous one");
    }
  }
  if (!information.empty() && information.size() != keyframe_t_ns.size()) {
    throw std::invalid_argument("odometry information: expected one matrix per keyframe (" +
                                std::to_string(keyframe_t_ns.size()) + "), got " +
                                std::to_string(information.size()));
  }
  std::vector<Pose3> at_keyframes;
  at_keyframes.reserve(keyframe_t_ns.size());
  for (size_t k = 0; k < keyframe_t_ns.size(); ++k) {
    if (k > 0 && keyframe_t_ns[k] <= keyframe_t_ns[k - 1]) {
      throw std::invalid_argument("keyframe " + std::to_string(k) +
                                  ": timestamp not after the previous one");
    }
    try {
      at_keyframes.push_back(interpolate_pose(odometry, keyframe_t_ns[k]));
    } catch (const std::out_of_range& e) {
      throw std::invalid_argument("keyframe " + std::to_string(k) + ": odometry " + e.what());
    }
  }
  std::vector<RelativePoseMeasurement> edges;
  for (size_t k = 1; k < keyframe_t_ns.size(); ++k) {
    RelativePoseMeasurement m;
    m.t_i_ns = keyframe_t_ns[k - 1];
    m.t_j_ns = keyframe_t_ns[k];
    m.T_i_j = at_keyframes[k - 1].inverse() * at_keyframes[k];
    m.information = information.empty() ? noise.information(m.T_i_j) : information[k];
    edges.push_back(m);
  }
  return edges;
}

}  // namespace keel::slam
