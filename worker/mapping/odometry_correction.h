// Algorithm 2, seed 000: high-rate, locally consistent odometry T_W'B (W' = the odometry's
// drifting world) corrected by low-rate, globally consistent MAP poses T_WB. Chainable as the
// paper does in Sec. VI-C: lidar odometry corrected by MAP keyframes, then IMU odometry corrected
// by the corrected lidar odometry, so every scan of every sensor finds a pose.
#pragma once

#include <cstddef>

#include "core/pose.h"

namespace keel::mapping {

struct OdometryCorrectionOptions {
  // Odometry samples before the first / after the last correction stamp: true keeps them with
  // the nearest correction held constant (the odometry is locally consistent there, which is
  // what the SLAM system itself relies on between keyframes); false drops them.
  bool hold_correction_outside = true;
};

struct OdometryCorrection {
  // Lines 3-17: T_WW' at the MAP stamps inside the odometry's span (T_world_body holds T_WW').
  Trajectory corrections;
  // Lines 18-25: T_WB^refined at the odometry stamps.
  Trajectory refined;
  size_t map_poses_outside_odometry = 0;  // MAP stamps with no odometry around them (unused)
  size_t odometry_poses_dropped = 0;      // only with hold_correction_outside = false
};

// Throws std::invalid_argument (naming "MAP poses" / "odometry" and the index) for unsorted,
// duplicate or non-finite poses, and when no MAP stamp falls inside the odometry's span.
OdometryCorrection correct_odometry(const Trajectory& T_world_body_map,
                                    const Trajectory& T_odom_body,
                                    const OdometryCorrectionOptions& options = {});

}  // namespace keel::mapping
