// Vehicle motion along a SmoothPath: a speed profile (rest, smooth ramp, cruise, ramp, rest),
// heading along the path or fixed, and wave-induced roll/pitch/heave. Every quantity the
// inertial sensors need is analytic: position, velocity, acceleration, attitude and body rate.
#pragma once

#include <Eigen/Geometry>

#include <vector>

#include "tests/sim/smooth_path.h"

namespace keel::sim {

struct KinematicState {
  double t_s = 0.0;         // seconds since mission start
  Eigen::Vector3d p_world;  // body origin in world
  Eigen::Vector3d v_world;  // d/dt p_world
  Eigen::Vector3d a_world;  // d2/dt2 p_world
  Eigen::Quaterniond q_world_body;
  Eigen::Vector3d omega_body;  // angular velocity of body w.r.t. world, in body
  double path_s = 0.0;         // arc length travelled along the path
};

struct MotionOptions {
  double cruise_speed_mps = 1.2;  // seed 000 Sec. V-C: "input velocity of 1.20 m/s"
  double ramp_s = 4.0;            // smooth speed-up / slow-down time
  double start_rest_s = 2.0;      // stationary at the start (lets a refiner see gravity)
  bool yaw_follows_path = true;   // USV: heading along the path; HAUV: fixed heading
  double fixed_yaw_rad = 0.0;
  // Waves: sums of one sinusoid each, phases drawn from the seed.
  double roll_amplitude_rad = 0.02, roll_frequency_hz = 0.35;
  double pitch_amplitude_rad = 0.012, pitch_frequency_hz = 0.5;
  double heave_amplitude_m = 0.03, heave_frequency_hz = 0.45;
  // Times the scenario's path is flown in a row at cruise speed (ramps only at the very start
  // and end); the scenario joins each lap's end to the next lap's start (repeat_laps).
  int laps = 1;
};

constexpr int kMaxLaps = 1000;

// Waypoints of `laps` consecutive laps of `lap`, each lap's end joined to the next lap's start
// by `connector` (waypoints strictly between the two), for one SmoothPath through all of them:
// the path stays C2 across the joints and the vehicle does not stop between laps. laps = 1
// returns `lap` unchanged. Throws std::invalid_argument naming motion.laps for laps outside
// [1, kMaxLaps].
std::vector<Eigen::Vector3d> repeat_laps(const std::vector<Eigen::Vector3d>& lap,
                                         const std::vector<Eigen::Vector3d>& connector, int laps);

class PathMotion {
 public:
  PathMotion(SmoothPath path, const MotionOptions& options, uint64_t seed);

  KinematicState state(double t_s) const;
  // Time at which the vehicle comes to rest at the path's end.
  double end_time() const { return end_time_; }
  const SmoothPath& path() const { return path_; }
  const MotionOptions& options() const { return options_; }
  // Arc length s(t) and its first two time derivatives.
  void arc_length(double t_s, double* s, double* s_dot, double* s_ddot) const;

 private:
  SmoothPath path_;
  MotionOptions options_;
  double roll_phase_ = 0.0, pitch_phase_ = 0.0, heave_phase_ = 0.0;
  double end_time_ = 0.0;
};

// Euler (ZYX: yaw, pitch, roll) angles and rates to the body angular velocity.
Eigen::Vector3d euler_rates_to_body_rate(double roll, double pitch, double roll_dot,
                                         double pitch_dot, double yaw_dot);
Eigen::Quaterniond quaternion_from_euler(double roll, double pitch, double yaw);

}  // namespace keel::sim
