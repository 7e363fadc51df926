// M3C2 (Lague, Brodu & Leroux 2013, "Accurate 3D comparison of complex topography with
// terrestrial laser scanner", ISPRS J. 82): the change of a compared cloud B against a
// reference cloud A measured along the local normal at core points, with a confidence:
//   1. normal N at a core point i: the least-squares plane of A within a sphere of diameter D
//      (the normal scale) around i (B's when A has too few points there);
//   2. a cylinder of diameter d (the projection scale) and half-length max_depth along N
//      through i; the points of each cloud inside it, projected on N, give their mean
//      positions i1, i2, standard deviations sigma1, sigma2 (roughness) and counts n1, n2;
//   3. L_M3C2 = i2 - i1 (signed: positive where B lies on N's side of A);
//   4. LoD95 = +-1.96 (sqrt(sigma1^2 / n1 + sigma2^2 / n2) + reg)                 Eq. (1)
//      with reg the registration error; the change is significant where |L_M3C2| > LoD95.
// Core points are one per voxel of B (their centroid), so the work does not grow with the
// point density; every point of B takes its voxel's result (change_<sensor>.drc).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "worker/compare/nearest_index.h"
#include "worker/compare/point_grid.h"
#include "worker/compare/voxel_moments.h"

namespace keel::compare {

struct M3c2Options {
  // D: diameter of the normal neighbourhood. Lague et al. advise D >= 20-25 times the
  // roughness so the normal follows the structure, not the noise (1-2 cm here: 0.5 m).
  double normal_scale_m = 0.5;
  // d: diameter of the projection cylinder; Lague et al. choose it so that each cylinder holds
  // >= ~30 points per cloud (a 2 cm map: ~80 in 0.2 m).
  double projection_scale_m = 0.2;
  // Half-length of the cylinder: the largest change it can measure.
  double max_depth_m = 1.0;
  double core_spacing_m = 0.1;        // one core point per voxel of B of this side
  int min_points = 5;                 // per cloud in a cylinder; fewer: the change is undefined
  double registration_error_m = 0.0;  // reg of Eq. (1)
  double confidence_z = 1.96;         // 95 % two-sided
  int threads = 2;
  // Called every few thousand core points from the worker threads; may throw to stop.
  std::function<void()> check_canceled;
};

// Throws std::invalid_argument naming the field for a value out of range.
void validate(const M3c2Options& options);

inline constexpr float kUndefined = std::numeric_limits<float>::quiet_NaN();

struct CoreChange {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  float distance_m = kUndefined;  // L_M3C2; NaN when a cylinder holds < min_points of a cloud
  float lod95_m = kUndefined;
  float sigma_a_m = kUndefined, sigma_b_m = kUndefined;
  float statistical_m = kUndefined;  // sqrt(sigma1^2 / n1 + sigma2^2 / n2) of Eq. (1)
  uint32_t count_a = 0, count_b = 0;
  bool significant = false;
  // Surface area the core point stands for: a plane of unit normal n cuts |n|_1 / s^2 voxels of
  // side s per square metre, so each core voxel holds s^2 / |n|_1 of it.
  float area_m2 = 0.0f;
  bool defined() const { return distance_m == distance_m; }
};

struct M3c2Clouds {
  const NearestIndex* reference = nullptr;  // A
  const NearestIndex* compared = nullptr;   // B
  // A's voxel moments (any voxel side <= D / 4), for the normals.
  const VoxelMoments* reference_voxels = nullptr;
  const VoxelMoments* compared_voxels = nullptr;  // B's, the fallback for normals
  // When both are given they gather the cylinders' points instead of the kd-trees (which may
  // then be null): on dense maps they read only the cells along a cylinder's axis.
  const PointGrid* reference_grid = nullptr;
  const PointGrid* compared_grid = nullptr;
};

// Recomputes every defined core's LoD95 and significance for another registration error.
void apply_registration_error(std::vector<CoreChange>* cores, double registration_error_m,
                              double confidence_z = 1.96);

// The same with each core's own registration error (per tile, compare/local_registration.h);
// `significant` is decided at significance_z with its own reg (each calibrated to its
// confidence), lod95_m at confidence_z.
void apply_registration_errors(std::vector<CoreChange>* cores,
                               const std::vector<double>& registration_error_m, double confidence_z,
                               const std::vector<double>& significance_reg_m,
                               double significance_z);

// Orients each normal towards the viewpoints (the sensor positions that saw the surface, so a
// positive change is material added towards the sensor): the nearest within 30 m that looks
// at the surface within 60 degrees of its normal, else the nearest; with no viewpoints,
// upwards (+z, CloudCompare's default preferred orientation), then +x, then +y on a tie.
std::vector<CoreChange> m3c2(const M3c2Clouds& clouds, const std::vector<Eigen::Vector3f>& cores,
                             const std::vector<Eigen::Vector3f>& viewpoints,
                             const M3c2Options& options);

}  // namespace keel::compare
