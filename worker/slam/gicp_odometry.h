// Relative poses between consecutive keyframe scans by GICP scan matching (PCL), for missions
// without recorded odometry; each carries the point-to-plane information of the converged
// alignment, whose small eigenvalues reveal degenerate geometry (refine_solver.h). Kept out of
// keel_slam so only its users compile against PCL.
#pragma once

#include <vector>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "worker/slam/relative_pose.h"

namespace keel::slam {

struct GicpOdometryOptions {
  double voxel_leaf_m = 0.2;  // downsampling before matching
  int max_iterations = 50;
  double max_correspondence_m = 1.0;
  double transformation_epsilon = 1e-8;
  int normal_neighbors = 10;         // plane fit for the information
  double max_planarity_ratio = 0.1;  // lambda_min / sum(lambda) of a usable plane
  // Point-to-plane residual sigma for the information H = sum J^T J / sigma^2. Neighbouring
  // residuals are not independent, so this is deliberately larger than the range noise.
  double point_sigma_m = 0.05;
  // Outlier gate: a converged alignment farther than this from the initial guess (the online
  // map's relative pose, good to centimetres) is a wrong local minimum, e.g. a spinning lidar's
  // rings matched to their neighbours over a flat surface, which shifts z by a ring spacing
  // while the point-to-plane information still looks confident. Such an edge gets zero
  // information (the refine stage then leaves it out). <= 0: no gate.
  double max_translation_from_guess_m = 0.25;
  double max_rotation_from_guess_rad = 0.1;
};

// scans[k]: the keyframe scan in the sensor frame, stamped with the keyframe time (t_ns);
// initial_T_world_body[k]: a guess of the keyframe pose (e.g. the online map pose). Returns the
// edges k-1 -> k (T_body_{k-1}_body_k, information in [t, phi] order); an edge that did not
// converge or failed the outlier gate keeps the guess with zero information. Throws
// std::invalid_argument on size mismatch, unsorted stamps or a scan with too few points.
std::vector<RelativePoseMeasurement> relative_poses_from_scans(
    const std::vector<PointCloud>& scans, const Pose3& T_body_sensor,
    const std::vector<Pose3>& initial_T_world_body, const GicpOdometryOptions& options = {});

// The point-to-plane information (6x6, [t, phi]) of aligning `source` onto `target` with the
// relative pose T_target_source; both clouds in their own body frames. Exposed for tests.
Matrix6d point_to_plane_information(const PointCloud& target, const PointCloud& source,
                                    const Pose3& T_target_source,
                                    const GicpOdometryOptions& options = {});

}  // namespace keel::slam
