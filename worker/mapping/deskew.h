// Motion compensation of one scan (seed 000 Sec. VI-A2): each point v_k is moved from the
// sensor pose at its own capture time into the sensor frame at the scan stamp,
//   p_ref = T_world_sensor(t_ns)^-1 * T_world_sensor(t_ns + time_s[k]) * p_k.
// Rather than one TF lookup per point (what the authors' MapBuilder does), the body pose is
// looked up once per scan at the sweep's first and last point times plus every trajectory
// stamp in between ("knots"); per point, the knots bracketing its time are slerped/lerped.
// Because the trajectory itself is piecewise slerp/lerp between its stamps, this equals the
// per-point lookup exactly, at one binary search per scan.
#pragma once

#include <string>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "worker/mapping/transform_tree.h"

namespace keel::mapping {

struct DeskewOptions {
  // Per-point times (seconds relative to the scan stamp) spanning more than this are refused:
  // the usual cause is a unit mistake (Ouster's nanosecond stamps read as seconds, absolute
  // times stored as offsets), which would otherwise smear the scan over the trajectory.
  double max_sweep_duration_s = 1.0;
};

// Deskews `scan` in place when it has per-point times (otherwise leaves it unchanged) and
// returns T_world_sensor at the scan stamp. Throws std::out_of_range (naming the time and the
// trajectory span) when the stamp or any point time is outside the trajectory, and
// std::invalid_argument for non-finite times or a sweep longer than max_sweep_duration_s.
Pose3 deskew_scan(const TransformTree& tree, const std::string& sensor, PointCloud& scan,
                  const DeskewOptions& options = {});

}  // namespace keel::mapping
