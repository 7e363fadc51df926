// One tile's rigid correction of survey B against survey A, estimated from the M3C2 change at
// B's core points (Lague et al. 2013) on structure that is stable in both surveys only, so a
// real change (a spall, a new object) is measured, never absorbed:
//   - the change at a core point i under a small motion x = [L w; t] of B about the tile's
//     centre c is d_i + J_i x, J_i = [((p_i - c) x n_i) / L, n_i] (point-to-plane, linear);
//   - the noise of d is the tile's own: 1.4826 MAD of the differences between neighbouring
//     core points / sqrt(2), which neither a tile-wide offset nor a change's interior moves;
//   - stable cores: |d_i + J_i x| within significance_sigmas noises (at least stable_floor_m),
//     and no changed core within leave_out_radius_m (a change's rim leans towards it);
//   - x by Huber-weighted least squares (Huber 1964, k = 1.345 noises) on the stable cores,
//     alternated with the stable set until it settles, from two starts: no correction (the
//     global registration) and the dominant offset of all cores; the second is kept only when
//     it makes markedly more cores stable than the first;
//   - x is solved only along the eigenvectors of the normal matrix H = sum w J J^T whose
//     eigenvalue is a fair share of its trace (directions the stable structure constrains: a
//     single wall fixes its normal's translation and the two tilts out of it, not the slide
//     along it); the others stay at the global registration;
//   - a correction that leaves less than min_support_fraction of the cores stable, or larger
//     than max_translation_m / max_rotation_deg, is not applied.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

#include "core/pose.h"

namespace keel::compare {

struct CoreSample {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit; d is measured along it
  double distance_m = 0.0;                            // M3C2 change, B - A along normal
  double statistical_m = 0.0;                         // sqrt(s1^2 / n1 + s2^2 / n2) of Eq. (1)
};

struct TileCorrectionOptions {
  double significance_sigmas = 3.0;
  double stable_floor_m = 0.01;  // the stable band is never narrower than this
  // The same for the calibration of reg (tile_registration_error): wider, so that the
  // registration's own error, which it measures, is not cut from its tail.
  double calibration_floor_m = 0.02;
  double leave_out_radius_m = 0.5;
  double huber_k = 1.345;  // in noises: 95 % efficiency on Gaussian residuals
  // A direction is fixed when its eigenvalue of H is at least this fraction of trace(H) / 6.
  double min_eigenvalue_fraction = 0.05;
  size_t min_stable_cores = 100;
  double min_support_fraction = 0.5;
  // The dominant-offset start wins only with this many more stable cores (fraction of all).
  double min_support_gain = 0.1;
  int max_rounds = 20;
  double max_translation_m = 0.1;
  double max_rotation_deg = 0.5;
};

struct TileCorrection {
  // "corrected", or why not: "too few cores", "no constrained direction", "unsupported",
  // "too large".
  std::string status;
  bool applied() const { return status == "corrected"; }
  Pose3 T_corrected_b = Pose3::Identity();  // identity unless applied
  double correction_m = 0.0;                // |translation| at the tile's centre
  size_t cores = 0, stable = 0;
  double noise_m = 0.0;  // the tile's noise of d (see above)
  // The fixed eigen-directions, each named by its largest component of [L w; t]: "tx", "ty",
  // "tz" (translations), "rx", "ry", "rz" (rotations).
  std::vector<std::string> fixed_directions;
};

TileCorrection correct_tile(const std::vector<CoreSample>& cores, const Eigen::Vector3d& center_m,
                            double half_side_m, const TileCorrectionOptions& options);

// The tile's noise of d: 1.4826 MAD of d_i - d_j (j the nearest other core within radius_m)
// / sqrt(2); 0 without pairs.
double neighbour_noise(const std::vector<CoreSample>& cores, double radius_m);

// Which cores are stable at residuals `residual_m`: |r| <= band and no core with |r| > band
// within radius_m.
std::vector<char> stable_cores(const std::vector<CoreSample>& cores,
                               const std::vector<double>& residual_m, double band_m,
                               double radius_m);

// The registration error of Eq. (1) left in a tile after registration (Lague et al.'s `reg`),
// calibrated so that the level of detection holds its confidence on the tile's stable
// structure: the smallest reg >= 0 with |d_i| <= z (statistical_i + reg) at a fraction
// 2 Phi(z) - 1 of its stable cores (95 % for z = 1.96), i.e. that quantile of
// |d_i| / z - statistical_i. Eq. (1)'s statistical term alone holds for independent noise;
// the registration's error and noise correlated over a scan (a trajectory's) widen |d| beyond
// it, by an amount this measures. The stable band is significance_sigmas times the larger of
// neighbour_noise and the spread of all its cores (1.4826 median |d|), at least
// calibration_floor_m. `stable` (optional) receives which cores are stable. -1 with fewer than
// min_stable_cores stable cores.
double tile_registration_error(const std::vector<CoreSample>& cores, double confidence_z,
                               const TileCorrectionOptions& options,
                               std::vector<char>* stable = nullptr);

}  // namespace keel::compare
