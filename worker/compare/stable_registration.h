// Registration of a later survey B onto an earlier survey A restricted to stable structure:
// point-to-plane ICP (Chen & Medioni 1992) from B's voxel centroids to A's local planes, where
// each iteration keeps only the pairs whose residual is small against the residuals' robust
// spread (|r| < k * 1.4826 MAD, at least a floor): structure that changed (new objects, spalls,
// fouling) moves its pairs' residuals out of the band and stops pulling on the transform.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <vector>

#include "core/pose.h"

namespace keel::compare {

struct StableRegistrationOptions {
  double sample_spacing_m = 0.2;      // B is sampled on voxels of this side (centroids)
  double plane_radius_m = 0.3;        // A's local planes: least squares within this radius
  double max_correspondence_m = 0.5;  // pairs farther apart are never used
  double stable_sigmas = 3.0;         // k of the stable band
  double stable_floor_m = 0.005;      // the band is never narrower than this
  double max_planar_ratio = 0.2;      // A's plane kept when l0 / l1 <= this (a surface)
  int max_iterations = 50;
  double converged_translation_m = 1e-5;  // a step smaller than both ends the iterations
  double converged_rotation_rad = 1e-6;
  int threads = 2;
  std::function<void()> check_canceled;
};

// Throws std::invalid_argument naming the field for a value out of range.
void validate(const StableRegistrationOptions& options);

struct StableRegistration {
  Pose3 T_a_b = Pose3::Identity();  // maps B's points into A's frame
  int iterations = 0;
  bool converged = false;
  size_t samples = 0;          // B's voxel centroids
  size_t correspondences = 0;  // pairs within max_correspondence_m at the end
  size_t stable = 0;           // of those, inside the stable band
  double band_m = 0.0;         // the stable band's half-width at the end
  double rms_stable_m = 0.0;   // RMS point-to-plane residual of the stable pairs
  // Smallest / largest eigenvalue of the normal equations (J^T J, rotation in rad, translation
  // in m): near 0 the structure does not fix the transform (a straight corridor).
  double conditioning = 0.0;
};

// Throws std::invalid_argument for empty clouds or non-finite points, std::runtime_error when
// fewer than 6 stable pairs remain.
StableRegistration register_stable(const std::vector<Eigen::Vector3f>& reference,
                                   const std::vector<Eigen::Vector3f>& moving,
                                   const Pose3& T_a_b_initial,
                                   const StableRegistrationOptions& options = {});

}  // namespace keel::compare
