// Trajectory accuracy metrics computed as Zhang & Scaramuzza (IROS 2018, seed 000 ref. [37])
// define them and as evo (github.com/MichaelGrupp/evo) computes them, so figures are comparable
// with the literature: ATE after Umeyama alignment (SE(3), Sim(3) or none), RPE over index or
// path-length deltas, and evo-style timestamp association. Pure math on keel::Trajectory.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "core/pose.h"

namespace keel::slam {

enum class Alignment { kNone, kSE3, kSim3 };

// y ~= scale * R * x + t.
struct SimilarityTransform {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return scale * R * x + t; }
  // The pose moved by the alignment: R' = R R_x, t' = scale R t_x + t (evo: scale, transform).
  Pose3 apply(const Pose3& T) const;
};

// Umeyama (TPAMI 1991), least squares of sum |y_k - (c R x_k + t)|^2 with det R = +1; c = 1
// unless with_scale. Throws std::invalid_argument for mismatched sizes, fewer than 3 points or
// degenerate (collinear / coincident) point sets.
SimilarityTransform umeyama_alignment(const std::vector<Eigen::Vector3d>& x,
                                      const std::vector<Eigen::Vector3d>& y, bool with_scale);

struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0.0, mean = 0.0, median = 0.0, std = 0.0, min = 0.0, max = 0.0;
};
// std is the population standard deviation (numpy's default, as evo reports it); median
// averages the two middle values of an even count.
ErrorStatistics error_statistics(std::vector<double> errors);

// evo's associate_trajectories: each stamp of the shorter trajectory is matched to the
// nearest stamp of the longer one (the first on ties), kept if |dt| <= max_difference_s;
// time_offset_s is added to the estimate's stamps.
struct AssociationOptions {
  double max_difference_s = 0.01;
  double time_offset_s = 0.0;
};
struct Association {
  std::vector<size_t> reference_index;
  std::vector<size_t> estimate_index;
};
Association associate_by_time(const Trajectory& reference, const Trajectory& estimate,
                              const AssociationOptions& options = {});

struct AteResult {
  ErrorStatistics translation_m;  // |t_est' - t_ref|
  ErrorStatistics rotation_deg;   // angle of R_ref^T R_est'
  SimilarityTransform alignment;  // applied to the estimate
  std::vector<double> translation_errors_m;
};

// ATE of poses paired by index (same index = same time).
AteResult absolute_trajectory_error(const std::vector<Pose3>& reference,
                                    const std::vector<Pose3>& estimate, Alignment alignment);
// ATE of stamped trajectories: associates first. Throws when nothing associates.
AteResult absolute_trajectory_error(const Trajectory& reference, const Trajectory& estimate,
                                    Alignment alignment, const AssociationOptions& options = {});

enum class DeltaUnit { kFrames, kMeters };
struct RpeOptions {
  double delta = 1.0;
  DeltaUnit unit = DeltaUnit::kFrames;
  // false: consecutive, non-overlapping pairs (evo's default); true: every start index.
  bool all_pairs = false;
  // kMeters with all_pairs: accept a pair when its path length is within delta * rel_tolerance
  // of delta (evo's rel_tol).
  double rel_tolerance = 0.1;
  Alignment alignment = Alignment::kNone;  // applied before (matters for Sim(3) scale)
  // kMeters: measure the path on the reference instead of the (aligned) estimate; evo uses
  // the estimate unless told otherwise (its pairs_from_reference).
  bool pairs_from_reference = false;
};
struct RpeResult {
  ErrorStatistics translation_m;  // |t(E)|, E = (T_ref_i^-1 T_ref_j)^-1 (T_est_i^-1 T_est_j)
  ErrorStatistics rotation_deg;   // angle(R(E))
  std::vector<std::pair<size_t, size_t>> pairs;
};
// Pairs follow evo's filters: frames: (0, d), (d, 2d), ... or (i, i+d) for all i; meters:
// indices where the travelled path first reaches k * delta, or for all_pairs the index j whose
// path length from i is nearest delta (within the tolerance; evo finds such a j by a bounded
// binary search, which may settle on a different one inside the tolerance).
// Throws std::invalid_argument when no pair exists or sizes differ.
RpeResult relative_pose_error(const std::vector<Pose3>& reference,
                              const std::vector<Pose3>& estimate, const RpeOptions& options = {});
RpeResult relative_pose_error(const Trajectory& reference, const Trajectory& estimate,
                              const RpeOptions& options = {},
                              const AssociationOptions& association = {});

}  // namespace keel::slam
