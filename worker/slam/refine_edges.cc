#include "worker/slam/refine_edges.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "worker/slam/information.h"
#include "worker/slam/so3.h"

namespace keel::slam {

void validate_keyframes(const Trajectory& keyframes) {
  if (keyframes.size() < 2) {
    throw std::invalid_argument("keyframes: expected at least 2, got " +
                                std::to_string(keyframes.size()));
  }
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const Pose3& T = keyframes[k].T_world_body;
    if (!T.matrix().allFinite()) {
      throw std::invalid_argument("keyframes[" + std::to_string(k) + "]: pose is not finite");
    }
    if (k > 0 && keyframes[k].t_ns <= keyframes[k - 1].t_ns) {
      throw std::invalid_argument("keyframes[" + std::to_string(k) +
                                  "]: timestamp not after the previous keyframe's");
    }
  }
}

namespace {

int keyframe_index(const std::vector<TimeNs>& t_ns, TimeNs query, TimeNs tolerance_ns,
                   const std::string& what) {
  auto it = std::lower_bound(t_ns.begin(), t_ns.end(), query);
  int best = -1;
  TimeNs best_diff = 0;
  for (auto c : {it, it == t_ns.begin() ? it : it - 1}) {
    if (c == t_ns.end()) continue;
    const TimeNs diff = std::abs(*c - query);
    if (best < 0 || diff < best_diff) {
      best = static_cast<int>(c - t_ns.begin());
      best_diff = diff;
    }
  }
  if (best < 0 || best_diff > tolerance_ns) {
    throw std::invalid_argument(what + ": stamp " + format_seconds(query) +
                                " s matches no keyframe within the tolerance");
  }
  return best;
}

// Information of a body-frame relative pose expressed for the IMU-frame relative pose
// X^-1 T X (X = T_body_imu), to first order: delta_imu = J delta_body with
// J = [R_X^T, -R_X^T R_ij (t_X)^; 0, R_X^T].
Matrix6d information_in_imu_frame(const Matrix6d& info_body, const Pose3& T_i_j_body,
                                  const Pose3& T_body_imu) {
  const Eigen::Matrix3d RXt = T_body_imu.linear().transpose();
  Matrix6d J = Matrix6d::Zero();
  J.block<3, 3>(0, 0) = RXt;
  J.block<3, 3>(0, 3) = -RXt * T_i_j_body.linear() * hat(T_body_imu.translation());
  J.block<3, 3>(3, 3) = RXt;
  const Matrix6d J_inv = J.inverse();
  return J_inv.transpose() * info_body * J_inv;
}

KeyframeEdge make_edge(const RelativePoseMeasurement& m, const Matrix6d& info_body, int i, int j,
                       const Pose3& T_body_imu) {
  KeyframeEdge e;
  e.i = i;
  e.j = j;
  e.T_i_j = T_body_imu.inverse() * m.T_i_j * T_body_imu;
  e.sqrt_info = sqrt_information(information_in_imu_frame(info_body, m.T_i_j, T_body_imu));
  return e;
}

void check_measurement(const RelativePoseMeasurement& m, const std::string& what) {
  if (!m.T_i_j.matrix().allFinite() || !m.information.allFinite()) {
    throw std::invalid_argument(what + ": pose or information is not finite");
  }
}

}  // namespace

// Step 2: odometry edges and per-keyframe degeneracy (Sec. IV-B).
std::vector<KeyframeEdge> odometry_edges(const RefineInput& in, const RefineOptions& opt,
                                         const std::vector<TimeNs>& t_ns,
                                         std::vector<KeyframeEstimate>* kf) {
  std::vector<KeyframeEdge> edges;
  if (!opt.use_odometry) return edges;
  const TimeNs tol = seconds_to_ns(opt.measurement_time_tolerance_s);
  for (size_t n = 0; n < in.odometry.size(); ++n) {
    const RelativePoseMeasurement& m = in.odometry[n];
    const std::string what = "odometry[" + std::to_string(n) + "]";
    check_measurement(m, what);
    const int i = keyframe_index(t_ns, m.t_i_ns, tol, what + ".t_i");
    const int j = keyframe_index(t_ns, m.t_j_ns, tol, what + ".t_j");
    if (i == j)
      throw std::invalid_argument(what + ": both stamps match keyframe " + std::to_string(i));
    const DegeneracyReport report = analyze_degeneracy(m.information, opt.degeneracy);
    KeyframeEstimate& target = (*kf)[std::max(i, j)];
    target.odometry_degeneracy = report;
    target.degenerate = target.degenerate || report.degenerate;
    Matrix6d info = m.information;
    if (report.degenerate) {
      if (opt.degeneracy_handling == DegeneracyHandling::kDropFactor) continue;
      if (opt.degeneracy_handling == DegeneracyHandling::kKeepWellConditioned) {
        info = report.well_conditioned_information;
      }
    }
    edges.push_back(make_edge(m, info, i, j, in.T_body_imu));
    target.has_odometry_factor = true;
  }
  return edges;
}

std::vector<KeyframeEdge> loop_edges(const RefineInput& in, const RefineOptions& opt,
                                     const std::vector<TimeNs>& t_ns) {
  std::vector<KeyframeEdge> edges;
  if (!opt.use_loop_closures) return edges;
  const TimeNs tol = seconds_to_ns(opt.measurement_time_tolerance_s);
  for (size_t n = 0; n < in.loop_closures.size(); ++n) {
    const RelativePoseMeasurement& m = in.loop_closures[n];
    const std::string what = "loop_closures[" + std::to_string(n) + "]";
    check_measurement(m, what);
    const int i = keyframe_index(t_ns, m.t_i_ns, tol, what + ".t_i");
    const int j = keyframe_index(t_ns, m.t_j_ns, tol, what + ".t_j");
    if (i == j)
      throw std::invalid_argument(what + ": both stamps match keyframe " + std::to_string(i));
    edges.push_back(make_edge(m, m.information, i, j, in.T_body_imu));
  }
  return edges;
}
}  // namespace keel::slam
