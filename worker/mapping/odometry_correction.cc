#include "worker/mapping/odometry_correction.h"

#include <stdexcept>

#include "worker/mapping/stamped_transforms.h"

namespace keel::mapping {
namespace {

// Lines 3-17 of Algorithm 2. The paper takes, for MAP pose j, the first odometry sample i with
// t_i >= t_j and forms T_WW' = tfMAP(t_i) * (T_W'B,i)^-1, interpolating the *low-rate* MAP
// poses at t_i and advancing j by one per hit (so a MAP pose is skipped whenever two fall
// between odometry samples, and j can run past the last MAP pose). Here the correction is
// formed exactly at each MAP stamp, interpolating the *high-rate* odometry instead:
// T_WW'(t_j) = T_WB^MAP(t_j) * T_W'B^odom(t_j)^-1. When stamps coincide (keyframes are
// odometry samples, as in LVI-SAM) both give the same value; otherwise this one interpolates
// the smoother, denser series and uses every MAP pose once.
Trajectory corrections_at_map_stamps(const Trajectory& T_world_body_map,
                                     const StampedTransforms& odometry, size_t* outside) {
  Trajectory corrections;
  corrections.reserve(T_world_body_map.size());
  for (const StampedPose& map_pose : T_world_body_map) {
    if (!odometry.covers(map_pose.t_ns)) {
      ++*outside;
      continue;
    }
    StampedPose correction;
    correction.t_ns = map_pose.t_ns;
    correction.T_world_body = map_pose.T_world_body * odometry.at(map_pose.t_ns).inverse();
    corrections.push_back(correction);
  }
  return corrections;
}

}  // namespace

OdometryCorrection correct_odometry(const Trajectory& T_world_body_map,
                                    const Trajectory& T_odom_body,
                                    const OdometryCorrectionOptions& options) {
  // Line 2: validate both series (sorted, unique, finite) by building their interpolators.
  const StampedTransforms map_poses(T_world_body_map, "MAP poses");
  const StampedTransforms odometry(T_odom_body, "odometry");

  OdometryCorrection result;
  result.corrections =
      corrections_at_map_stamps(T_world_body_map, odometry, &result.map_poses_outside_odometry);
  if (result.corrections.empty()) {
    throw std::invalid_argument("Algorithm 2: no MAP pose lies inside the odometry span [" +
                                format_seconds(odometry.begin_ns()) + ", " +
                                format_seconds(odometry.end_ns()) + "] s (MAP poses span [" +
                                format_seconds(map_poses.begin_ns()) + ", " +
                                format_seconds(map_poses.end_ns()) + "] s)");
  }
  const StampedTransforms tf_correct(result.corrections, "odometry corrections");

  // Lines 18-25: T_WB^refined(t_i) = T_WW'^interp(t_i) * T_W'B^odom,i.
  result.refined.reserve(T_odom_body.size());
  for (const StampedPose& odom : T_odom_body) {
    if (!tf_correct.covers(odom.t_ns) && !options.hold_correction_outside) {
      ++result.odometry_poses_dropped;
      continue;
    }
    StampedPose refined;
    refined.t_ns = odom.t_ns;
    refined.T_world_body = tf_correct.at_clamped(odom.t_ns) * odom.T_world_body;
    result.refined.push_back(refined);
  }
  return result;
}

}  // namespace keel::mapping
