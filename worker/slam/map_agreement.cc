#include "worker/slam/map_agreement.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

// sqrt(d^T Sigma^-1 d).
double mahalanobis(const Eigen::Vector3d& d, const Eigen::Matrix3d& sigma, const char* what) {
  const Eigen::LLT<Eigen::Matrix3d> llt(0.5 * (sigma + sigma.transpose()));
  if (llt.info() != Eigen::Success)
    throw std::invalid_argument(std::string("MAP ") + what +
                                " covariance is not positive definite");
  return llt.matrixL().solve(d).norm();
}

}  // namespace

MapAgreement compare_with_map(const Trajectory& map, const Trajectory& refined,
                              const MapPoseNoise& noise, const std::vector<double>& drift_path_m,
                              double chi2_threshold) {
  if (map.size() != refined.size() || map.size() != drift_path_m.size())
    throw std::invalid_argument("self-check: " + std::to_string(map.size()) + " MAP poses but " +
                                std::to_string(refined.size()) + " refined poses and " +
                                std::to_string(drift_path_m.size()) + " drift path lengths");
  for (size_t k = 0; k < map.size(); ++k) {
    if (map[k].t_ns != refined[k].t_ns)
      throw std::invalid_argument("self-check: refined pose " + std::to_string(k) +
                                  " is not at the MAP keyframe's stamp");
  }
  const double threshold = std::sqrt(chi2_threshold);
  MapAgreement out;
  out.chi2_threshold = chi2_threshold;
  double sum_t = 0.0, sum_r = 0.0;
  for (size_t k = 0; k < map.size(); ++k) {
    KeyframeMovement m;
    m.t_ns = map[k].t_ns;
    const Pose3& T_map = map[k].T_world_body;
    m.translation_m = refined[k].T_world_body.translation() - T_map.translation();
    m.rotation_rad = so3_log(T_map.linear().transpose() * refined[k].T_world_body.linear());
    m.drift_path_m = drift_path_m[k];
    m.mahalanobis_translation =
        mahalanobis(m.translation_m, noise.position_covariance(drift_path_m[k]), "position");
    m.mahalanobis_rotation = mahalanobis(m.rotation_rad, noise.rotation_covariance, "rotation");
    m.flagged = m.mahalanobis_translation > threshold || m.mahalanobis_rotation > threshold;
    out.flagged += m.flagged ? 1 : 0;
    sum_t += m.translation_m.squaredNorm();
    sum_r += m.rotation_rad.squaredNorm();
    out.translation_max_m = std::max(out.translation_max_m, m.translation_m.norm());
    out.rotation_max_rad = std::max(out.rotation_max_rad, m.rotation_rad.norm());
    out.keyframes.push_back(m);
  }
  if (!map.empty()) {
    out.translation_rms_m = std::sqrt(sum_t / static_cast<double>(map.size()));
    out.rotation_rms_rad = std::sqrt(sum_r / static_cast<double>(map.size()));
  }
  return out;
}

}  // namespace keel::slam
