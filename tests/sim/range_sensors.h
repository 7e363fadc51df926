// Range sensors simulated by ray casting: a VLP-16-like spinning lidar (seed 000 Table I)
// and a multibeam profiling sonar (seed 000 Sec. VI: Imagenex DT100).
#pragma once

#include "tests/sim/pose_table.h"
#include "tests/sim/rng.h"
#include "tests/sim/sim_world.h"
#include "core/point_cloud.h"

namespace keel::sim {

struct SpinningLidarOptions {  // seed 000 Table I
  int rings = 16;
  double elevation_min_deg = -15.0, elevation_max_deg = 15.0;  // 30 deg vertical coverage
  int points_per_ring = 1875;  // "points per revolution" of the Gazebo VLP-16 model
  double rate_hz = 10.0;
  double range_min_m = 0.1, range_max_m = 130.0;
  double range_sigma_m = 0.01;
};

// One sweep starting at t_start_s: column j fires at t_start + j / (points_per_ring * rate)
// from the pose the vehicle has then, so the points carry the motion during the sweep
// (deskew has work to do). Points in the sensor frame at their firing time; time_s is the
// offset from the sweep start; t_ns is left to the caller.
PointCloud simulate_lidar_sweep(const SimWorld& world, const PoseTable& poses,
                                const Pose3& T_body_sensor, double t_start_s,
                                const SpinningLidarOptions& options, Rng& rng);

struct ProfilingSonarOptions {
  int beams = 240;
  double fan_deg = 120.0;  // beams in the sensor x-z plane, centred on +x
  double rate_hz = 10.0;
  double range_min_m = 0.5, range_max_m = 50.0;
  double range_sigma_m = 0.02;
};

// One ping (instantaneous); points in the sensor frame with intensity.
PointCloud simulate_sonar_ping(const SimWorld& world, const Pose3& T_world_sensor,
                               const ProfilingSonarOptions& options, Rng& rng);

}  // namespace keel::sim
