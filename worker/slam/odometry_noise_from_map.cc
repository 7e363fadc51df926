#include "worker/slam/odometry_noise_from_map.h"

#include <Eigen/Cholesky>

#include "worker/slam/so3.h"

namespace keel::slam {

std::optional<Vector6d> odometry_disagreement_rms(
    const Trajectory& keyframes, const std::vector<RelativePoseMeasurement>& odometry) {
  if (keyframes.empty() || odometry.size() != keyframes.size() - 1) return std::nullopt;
  Vector6d sum = Vector6d::Zero();
  size_t used = 0;
  for (size_t k = 0; k < odometry.size(); ++k) {
    if (odometry[k].information.isZero()) continue;  // no measurement (a failed registration)
    const Pose3 T_map = keyframes[k].T_world_body.inverse() * keyframes[k + 1].T_world_body;
    const Pose3& T_odo = odometry[k].T_i_j;
    Vector6d e;
    e.head<3>() = T_odo.translation() - T_map.translation();
    e.tail<3>() = so3_log(T_map.linear().transpose() * T_odo.linear());
    sum += e.cwiseProduct(e);
    ++used;
  }
  if (used == 0) return std::nullopt;
  return Vector6d((sum / static_cast<double>(used)).cwiseSqrt());
}

Matrix6d widen_information(const Matrix6d& information, const Vector6d& sigma_added) {
  const Vector6d d_sqrt = sigma_added.cwiseMax(1e-6);
  const Matrix6d D_half = d_sqrt.asDiagonal();
  const Matrix6d D_inv_half = d_sqrt.cwiseInverse().asDiagonal();
  const Matrix6d M = D_half * information * D_half;
  // M and (I + M) commute, so M (I + M)^-1 = (I + M)^-1 M.
  const Matrix6d widened = D_inv_half * (Matrix6d::Identity() + M).ldlt().solve(M) * D_inv_half;
  return 0.5 * (widened + widened.transpose());
}

std::optional<Vector6d> widen_by_map_disagreement(const Trajectory& keyframes,
                                                  std::vector<RelativePoseMeasurement>& odometry) {
  const std::optional<Vector6d> rms = odometry_disagreement_rms(keyframes, odometry);
  if (!rms) return std::nullopt;
  for (auto& edge : odometry) edge.information = widen_information(edge.information, *rms);
  return rms;
}

}  // namespace keel::slam
