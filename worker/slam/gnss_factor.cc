#include "worker/slam/gnss_factor.h"

#include <algorithm>

#include "worker/slam/information.h"
#include "worker/slam/manifolds.h"
#include "worker/slam/so3.h"

namespace keel::slam {

std::vector<GnssPlacement> place_gnss_fixes(const std::vector<GnssFix>& fixes,
                                            const std::vector<TimeNs>& t_ns,
                                            const GnssOptions& options) {
  std::vector<GnssPlacement> out(fixes.size());
  const TimeNs max_gap = seconds_to_ns(options.max_interpolation_gap_s);
  for (size_t f = 0; f < fixes.size(); ++f) {
    const TimeNs t = fixes[f].t_ns;
    const auto it = std::upper_bound(t_ns.begin(), t_ns.end(), t);
    if (it == t_ns.begin()) continue;  // before the first keyframe
    long k = static_cast<long>(it - t_ns.begin()) - 1;
    if (it == t_ns.end()) {  // at or after the last keyframe: only exactly on it
      if (t != t_ns.back() || t_ns.size() < 2) continue;
      k = static_cast<long>(t_ns.size()) - 2;
    }
    const TimeNs t0 = t_ns[static_cast<size_t>(k)], t1 = t_ns[static_cast<size_t>(k) + 1];
    if (std::min(t - t0, t1 - t) > max_gap) continue;
    out[f] = {k, static_cast<double>(t - t0) / static_cast<double>(t1 - t0)};
  }
  return out;
}

GnssPositionFactor::GnssPositionFactor(const GnssFix& fix, double alpha,
                                       const Eigen::Vector3d& lever_imu)
    : z_(fix.antenna_world_m),
      sqrt_information_(sqrt_information_from_covariance(fix.covariance_m2)),
      alpha_(alpha),
      lever_(lever_imu) {}

Eigen::Vector3d GnssPositionFactor::whitened(const double* pose_i, const double* pose_j) const {
  const Eigen::Vector3d a_i = block_position(pose_i) + block_rotation(pose_i + 3) * lever_;
  const Eigen::Vector3d a_j = block_position(pose_j) + block_rotation(pose_j + 3) * lever_;
  return sqrt_information_ * ((1.0 - alpha_) * a_i + alpha_ * a_j - z_);
}

bool GnssPositionFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = whitened(parameters[0], parameters[1]);
  if (!jacobians) return true;
  // d/d(delta p) = w I; d/d(delta phi) = -w R [l]x  (R Exp(dphi) l = R l - R [l]x dphi).
  for (int b = 0; b < 2; ++b) {
    if (!jacobians[b]) continue;
    const double w = b == 0 ? 1.0 - alpha_ : alpha_;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = w * sqrt_information_;
    J.rightCols<3>() = -w * sqrt_information_ * block_rotation(parameters[b] + 3) * hat(lever_);
    set_lifted_jacobian<3, 6, 7>(J, jacobians[b]);
  }
  return true;
}

GnssCounts add_gnss_factors(ceres::Problem& problem, const std::vector<GnssFix>& fixes,
                            const std::vector<GnssPlacement>& placements,
                            const std::function<double*(size_t)>& pose_block,
                            const Eigen::Vector3d& lever_imu, const GnssOptions& options, bool gate,
                            std::vector<GnssFixUse>* use) {
  GnssCounts counts;
  use->assign(fixes.size(), GnssFixUse::kOutside);
  for (size_t f = 0; f < fixes.size(); ++f) {
    const GnssPlacement& p = placements[f];
    if (p.k < 0) {
      ++counts.outside;
      continue;
    }
    auto factor = std::make_unique<GnssPositionFactor>(fixes[f], p.alpha, lever_imu);
    double* pose_i = pose_block(static_cast<size_t>(p.k));
    double* pose_j = pose_block(static_cast<size_t>(p.k) + 1);
    if (gate && factor->whitened(pose_i, pose_j).squaredNorm() > options.gate_chi2) {
      (*use)[f] = GnssFixUse::kRejected;
      ++counts.rejected;
      continue;
    }
    ceres::LossFunction* loss = nullptr;
    if (!gate && options.first_pass_cauchy_scale > 0)
      loss = new ceres::CauchyLoss(options.first_pass_cauchy_scale);
    problem.AddResidualBlock(factor.release(), loss, pose_i, pose_j);
    (*use)[f] = GnssFixUse::kUsed;
    ++counts.used;
  }
  return counts;
}

}  // namespace keel::slam
