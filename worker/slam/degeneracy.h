// Degeneracy of a scan-matching (odometry) constraint from the eigenvalues of its information
// matrix (Zhang, Kaess, Singh, ICRA 2016: small eigenvalues of the Hessian = directions the
// scan matching cannot observe), and what the refine solver does about it (seed 000 Sec. IV-B:
// "fully relies on IMU and DVL factors when degeneracy is detected").
#pragma once

#include <Eigen/Core>

#include "worker/slam/relative_pose.h"

namespace keel::slam {

struct DegeneracyOptions {
  // Translation and rotation are judged separately so the thresholds have units: a direction
  // is degenerate when its information eigenvalue is below 1 / sigma_max^2, i.e. its standard
  // deviation exceeds 0.5 m (translation) or 0.1 rad (rotation).
  double min_eigenvalue_translation = 1.0 / (0.5 * 0.5);  // 1/m^2
  double min_eigenvalue_rotation = 1.0 / (0.1 * 0.1);     // 1/rad^2
  // Relative test: a direction whose eigenvalue is below this fraction of the block's largest
  // is degenerate too. Scan-matching Hessians grow with the number of points, so noisy normals
  // alone lift a corridor's axis above any fixed threshold; its condition number does not.
  double min_eigenvalue_ratio = 1e-2;
};

struct DegeneracyReport {
  bool degenerate = false;
  Eigen::Vector3d eigenvalues_translation = Eigen::Vector3d::Zero();  // ascending
  Eigen::Vector3d eigenvalues_rotation = Eigen::Vector3d::Zero();     // ascending
  // The information with the degenerate directions removed (the constraint's well-observed
  // part; zero where everything is degenerate).
  Matrix6d well_conditioned_information = Matrix6d::Zero();
};

// Eigen-decomposes the translation and rotation diagonal blocks of `information` ([t, phi]
// order) and flags eigenvalues under max(absolute threshold, ratio * largest eigenvalue).
DegeneracyReport analyze_degeneracy(const Matrix6d& information,
                                    const DegeneracyOptions& options = {});

}  // namespace keel::slam
