#include "worker/stages/refine/report_json.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace keel::pipeline {

namespace {

using nlohmann::json;

constexpr double kRadToDeg = 180.0 / M_PI;

// Standard deviations along the world (translation) or body (rotation) axes, and along the
// covariance's principal axes (largest first), in `unit_scale` units.
json covariance_json(const Eigen::Matrix3d& covariance, double unit_scale) {
  const Eigen::Vector3d axes = covariance.diagonal().cwiseMax(0.0).cwiseSqrt() * unit_scale;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(covariance);
  const Eigen::Vector3d principal = es.eigenvalues().cwiseMax(0.0).cwiseSqrt() * unit_scale;
  const Eigen::Vector3d largest = es.eigenvectors().col(2);
  return {{"axes", {axes.x(), axes.y(), axes.z()}},
          {"principal", {principal.z(), principal.y(), principal.x()}},
          {"largest_direction", {largest.x(), largest.y(), largest.z()}}};
}

}  // namespace

json solver_json(const slam::RefineSummary& s) {
  return {{"iterations", s.iterations},
          {"solve_time_s", s.solve_time_s},
          {"covariance_time_s", s.covariance_time_s},
          {"total_time_s", s.total_time_s},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"converged", s.converged},
          {"keyframes", s.num_keyframes},
          {"factors",
           {{"odometry", s.num_odometry_factors},
            {"imu", s.num_imu_factors},
            {"dvl", s.num_dvl_factors},
            {"loop_closures", s.num_loop_closures},
            {"map_anchors", s.num_map_anchors}}},
          {"intervals_skipped",
           {{"imu_gaps", s.num_imu_intervals_skipped}, {"dvl_gaps", s.num_dvl_intervals_skipped}}},
          {"pseudo_samples", s.num_pseudo_samples},
          {"covariance_ok", s.covariance_ok},
          {"ceres", s.ceres_report}};
}

json degenerate_json(const slam::RefineResult& r) {
  std::vector<TimeNs> t_ns;
  std::vector<bool> degenerate;
  for (const auto& k : r.keyframes) {
    t_ns.push_back(k.t_ns);
    degenerate.push_back(k.degenerate);
  }
  return {{"count", std::count(degenerate.begin(), degenerate.end(), true)},
          {"ranges", stamp_ranges(t_ns, degenerate)}};
}

json map_noise_json(const slam::RefineResult& r, bool anchors) {
  return {{"anchors", anchors},
          {"estimated", r.map_noise_estimated},
          {"sigma_translation_m", covariance_json(r.map_noise.translation_covariance, 1.0)},
          {"drift_m_per_sqrt_m", covariance_json(r.map_noise.drift_covariance_per_m, 1.0)},
          {"sigma_rotation_deg", covariance_json(r.map_noise.rotation_covariance, kRadToDeg)}};
}

json stamp_ranges(const std::vector<TimeNs>& t_ns, const std::vector<bool>& flagged) {
  json ranges = json::array();
  for (size_t k = 0; k < t_ns.size(); ++k) {
    if (!flagged[k]) continue;
    const double t = ns_to_seconds(t_ns[k]);
    if (k > 0 && flagged[k - 1]) {
      ranges.back()["t_last_s"] = t;
      ranges.back()["keyframes"] = ranges.back()["keyframes"].get<int>() + 1;
    } else {
      ranges.push_back({{"t_first_s", t}, {"t_last_s", t}, {"keyframes", 1}});
    }
  }
  return ranges;
}

}  // namespace keel::pipeline
