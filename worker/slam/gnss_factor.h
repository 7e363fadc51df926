// GNSS position factors for the refine graph (issue 30): a fix measures the antenna position in
// the world frame (the mission's local ENU frame). Fixes come between keyframes, so the antenna
// position at the fix's stamp is interpolated linearly between the two keyframes around it:
//   a(t) = (1 - alpha) (p_i + R_i l) + alpha (p_j + R_j l),   alpha = (t - t_i) / (t_j - t_i),
// with l the antenna's lever arm in the IMU frame (T_imu_gnss); residual S (a - z), S the fix's
// square-root information. At 1 Hz keyframes and USV speeds (~1 m/s, turns of ~5 m radius) the
// interpolation's chord error is a few cm, well under a fix's sigma.
//
// Gating: a fix whose squared Mahalanobis distance to the current estimate, (a - z)^T Sigma^-1
// (a - z), exceeds `gate_chi2` is left out of the graph (reflected signals under a bridge give
// fixes metres off with status "fix"). The first solve has no estimate to gate against but the
// initial values, so it keeps every fix under a Cauchy loss; the later passes gate against the
// previous pass's solution and use the accepted fixes plainly.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>

#include <functional>
#include <vector>

#include "core/time.h"

namespace keel::slam {

struct GnssFix {
  TimeNs t_ns = 0;
  Eigen::Vector3d antenna_world_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance_m2 = Eigen::Matrix3d::Identity();
};

struct GnssOptions {
  // chi-square with 3 degrees of freedom at p = 0.999 (a clean fix is rejected 1 time in 1000).
  double gate_chi2 = 16.266;
  double first_pass_cauchy_scale = 1.0;  // whitened units
  // Fixes further than this from both keyframes of their interval are not placed (a gap in the
  // keyframes is no place for linear interpolation).
  double max_interpolation_gap_s = 5.0;
};

enum class GnssFixUse { kUsed, kRejected, kOutside };

// Where a fix sits in the keyframes: between k and k + 1 at alpha in [0, 1]; k < 0 outside.
struct GnssPlacement {
  long k = -1;
  double alpha = 0.0;
};

std::vector<GnssPlacement> place_gnss_fixes(const std::vector<GnssFix>& fixes,
                                            const std::vector<TimeNs>& keyframe_t_ns,
                                            const GnssOptions& options);

class GnssPositionFactor : public ceres::SizedCostFunction<3, 7, 7> {
 public:
  GnssPositionFactor(const GnssFix& fix, double alpha, const Eigen::Vector3d& lever_imu);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  // The whitened residual of pose blocks (T_world_imu, manifolds.h layout).
  Eigen::Vector3d whitened(const double* pose_i, const double* pose_j) const;

 private:
  Eigen::Vector3d z_;
  Eigen::Matrix3d sqrt_information_;
  double alpha_;
  Eigen::Vector3d lever_;
};

struct GnssCounts {
  int used = 0, rejected = 0, outside = 0;
};

// Adds a factor per placed fix; `gate`: only fixes within options.gate_chi2 of the current
// values of the pose blocks (plain least squares), else every fix under a Cauchy loss.
// `use` gets each fix's fate.
GnssCounts add_gnss_factors(ceres::Problem& problem, const std::vector<GnssFix>& fixes,
                            const std::vector<GnssPlacement>& placements,
                            const std::function<double*(size_t)>& pose_block,
                            const Eigen::Vector3d& lever_imu, const GnssOptions& options, bool gate,
                            std::vector<GnssFixUse>* use);

}  // namespace keel::slam
