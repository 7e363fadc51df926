// Stream sensors: IMU (seed 000 Eq. (4)-(5)), DVL velocity (Eq. (8)/(10)), DVL Janus beam
// geometry, pressure depth and the HAUV servo angle (seed 001 Eq. (10)).
#pragma once

#include <Eigen/Core>

#include <array>
#include <functional>
#include <vector>

#include "tests/sim/motion.h"
#include "core/pose.h"

namespace keel::sim {

constexpr double kGravity = 9.81;  // docs/mission-format.md: +9.81 on z at rest

// Sample times t_k = k / rate in [0, duration], exact in nanoseconds.
std::vector<int64_t> sample_times_ns(double rate_hz, double duration_s);

struct ImuOptions {  // seed 000 Table I (Xsens MTi-30)
  double rate_hz = 200.0;
  double gyro_noise_density = 5.7e-4;   // rad/s/sqrt(Hz)
  double accel_noise_density = 9.4e-4;  // m/s^2/sqrt(Hz)
  double gyro_random_walk = 3.7e-6;     // rad/s^2/sqrt(Hz)
  double accel_random_walk = 2.4e-6;    // m/s^3/sqrt(Hz)
  bool noise = true;
};

struct ImuSample {
  int64_t t_ns;                 // since mission start
  Eigen::Vector3d gyro, accel;  // body rate (rad/s) and specific force (m/s^2), IMU = body frame
  Eigen::Vector3d gyro_bias, accel_bias;  // true biases at t
};

// Noise-free specific force R_wb^T (a_w - g_w), g_w = (0, 0, -9.81): Eq. (5) without b, eta.
Eigen::Vector3d specific_force(const KinematicState& state);

// Discrete-time white noise sigma = density * sqrt(rate); biases follow Eq. (6)/(7).
std::vector<ImuSample> simulate_imu(const PathMotion& motion, double duration_s,
                                    const ImuOptions& options, uint64_t seed);

struct DvlOptions {  // seed 000 Table I (Water Linked A50)
  double rate_hz = 20.0;
  double velocity_sigma_rel = 1e-3;    // sigma = 1e-3 |v|
  double bias_random_walk_rel = 1e-4;  // sigma_bv = 1e-4 |v| per sqrt(Hz)
  double scale = 1.0;                  // s_d of Eq. (8)
  double dropout_rate = 0.0;           // long-run fraction of samples lost
  double dropout_mean_length_s = 0.5;  // dropouts come in bursts
  bool noise = true;
};

struct DvlSample {
  int64_t t_ns;
  Eigen::Vector3d velocity;       // measured, DVL frame
  Eigen::Vector3d velocity_true;  // noise-free, unscaled
  bool valid = true;
};

// Noise-free DVL velocity: R_dvl_body (R_world_body^T v_world + omega x t_body_dvl).
Eigen::Vector3d dvl_velocity(const KinematicState& state, const Pose3& T_body_dvl);

// T_body_dvl(t): the DVL may ride a servo tray whose axis passes through the DVL origin.
// has_lock(t, T_body_dvl) false marks a sample invalid (no bottom/hull lock).
std::vector<DvlSample> simulate_dvl(
    const PathMotion& motion, double duration_s, const std::function<Pose3(double)>& T_body_dvl,
    const DvlOptions& options, uint64_t seed,
    const std::function<bool(double, const Pose3&)>& has_lock = nullptr);

// Four Janus beams at `angle_deg` from the DVL's +z boresight, in the x-z and y-z planes.
std::array<Eigen::Vector3d, 4> janus_beams(double angle_deg = 30.0);

struct ScalarSample {
  int64_t t_ns;
  double value;
  double value_true;
};

// Pressure depth (positive down) of the sensor origin.
std::vector<ScalarSample> simulate_depth(const PathMotion& motion, double duration_s,
                                         const Eigen::Vector3d& t_body_sensor, double rate_hz,
                                         double sigma_m, uint64_t seed);

// Servo angle: measured = true + N(0, sigma) (seed 001 Eq. (10), sigma = 5 deg).
std::vector<ScalarSample> simulate_servo(const std::function<double(double)>& angle_true,
                                         double duration_s, double rate_hz, double sigma_rad,
                                         uint64_t seed);

}  // namespace keel::sim
