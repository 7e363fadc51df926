#include "worker/slam/map_pose_noise.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

// The symmetric part of M with every eigenvalue raised to at least `floor`.
Eigen::Matrix3d clamp_eigenvalues(const Eigen::Matrix3d& M, double floor) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (M + M.transpose()));
  const Eigen::Vector3d values = es.eigenvalues().cwiseMax(floor);
  return es.eigenvectors() * values.asDiagonal() * es.eigenvectors().transpose();
}

// Least-squares fit of Y_n = A + B x_n (3x3 matrices, scalar x_n) over the samples.
struct MomentFit {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
};

MomentFit fit_moments(const std::vector<Eigen::Vector3d>& differences,
                      const std::vector<double>& x) {
  const double n = static_cast<double>(x.size());
  double x_mean = 0.0;
  Eigen::Matrix3d y_mean = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < x.size(); ++k) {
    x_mean += x[k] / n;
    y_mean += differences[k] * differences[k].transpose() / n;
  }
  double sxx = 0.0;
  Eigen::Matrix3d sxy = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < x.size(); ++k) {
    sxx += (x[k] - x_mean) * (x[k] - x_mean);
    sxy += (x[k] - x_mean) * (differences[k] * differences[k].transpose() - y_mean);
  }
  MomentFit fit;
  // No spread in drift path (no degenerate stretch, or the vehicle never moved): the
  // differences are white noise only.
  if (sxx > 1e-9) fit.B = sxy / sxx;
  fit.A = y_mean - fit.B * x_mean;
  return fit;
}

}  // namespace

MapPoseNoise MapPoseNoise::isotropic(double sigma_translation_m, double sigma_rotation_rad,
                                     double drift_per_sqrt_m) {
  MapPoseNoise n;
  n.translation_covariance =
      Eigen::Matrix3d::Identity() * sigma_translation_m * sigma_translation_m;
  n.rotation_covariance = Eigen::Matrix3d::Identity() * sigma_rotation_rad * sigma_rotation_rad;
  n.drift_covariance_per_m = Eigen::Matrix3d::Identity() * drift_per_sqrt_m * drift_per_sqrt_m;
  return n;
}

Eigen::Matrix3d MapPoseNoise::position_covariance(double path_m) const {
  return translation_covariance + drift_covariance_per_m * std::max(0.0, path_m);
}

std::vector<double> path_lengths(const std::vector<Pose3>& poses) {
  std::vector<double> s(poses.size(), 0.0);
  for (size_t k = 1; k < poses.size(); ++k)
    s[k] = s[k - 1] + (poses[k].translation() - poses[k - 1].translation()).norm();
  return s;
}

MapPoseNoise estimate_map_pose_noise(const std::vector<Pose3>& map,
                                     const std::vector<Pose3>& reference,
                                     const std::vector<double>& drift_path_m,
                                     const MapNoiseEstimateOptions& options) {
  if (map.size() != reference.size() || map.size() != drift_path_m.size())
    throw std::invalid_argument("MAP noise estimate: " + std::to_string(map.size()) +
                                " MAP poses but " + std::to_string(reference.size()) +
                                " reference poses and " + std::to_string(drift_path_m.size()) +
                                " drift path lengths");
  if (map.size() < 3)
    throw std::invalid_argument("MAP noise estimate: needs at least 3 poses, got " +
                                std::to_string(map.size()));
  const size_t n = map.size();
  const std::vector<double>& s = drift_path_m;
  std::vector<Eigen::Vector3d> e(n), rho(n);
  for (size_t k = 0; k < n; ++k) {
    e[k] = map[k].translation() - reference[k].translation();
    rho[k] = so3_log(reference[k].linear().transpose() * map[k].linear());
  }
  std::vector<Eigen::Vector3d> de, drho;
  std::vector<double> ds;
  const size_t max_lag = std::min<size_t>(std::max(1, options.max_lag), n - 1);
  for (size_t m = 1; m <= max_lag; ++m) {
    for (size_t k = m; k < n; ++k) {
      de.push_back(e[k] - e[k - m]);
      drho.push_back(rho[k] - rho[k - m]);
      ds.push_back(s[k] - s[k - m]);
    }
  }
  const MomentFit translation = fit_moments(de, ds);
  const MomentFit rotation = fit_moments(drho, ds);
  MapPoseNoise noise;
  const double t_floor = options.min_sigma_translation_m * options.min_sigma_translation_m;
  const double r_floor = options.min_sigma_rotation_rad * options.min_sigma_rotation_rad;
  const double d_floor = options.min_drift_per_sqrt_m * options.min_drift_per_sqrt_m;
  noise.translation_covariance = clamp_eigenvalues(0.5 * translation.A, t_floor);
  noise.drift_covariance_per_m = clamp_eigenvalues(translation.B, d_floor);
  // The rotation is modelled white: the intercept is its variance; a drift in rotation would
  // show as a slope, which the anchors do not model (the online SLAM's loops bound heading).
  noise.rotation_covariance = clamp_eigenvalues(0.5 * rotation.A, r_floor);
  return noise;
}

}  // namespace keel::slam
