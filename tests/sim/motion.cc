#include "tests/sim/motion.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "tests/sim/rng.h"

namespace keel::sim {

Eigen::Vector3d euler_rates_to_body_rate(double roll, double pitch, double roll_dot,
                                         double pitch_dot, double yaw_dot) {
  const double sr = std::sin(roll), cr = std::cos(roll);
  const double sp = std::sin(pitch), cp = std::cos(pitch);
  return {roll_dot - yaw_dot * sp, pitch_dot * cr + yaw_dot * cp * sr,
          -pitch_dot * sr + yaw_dot * cp * cr};
}

Eigen::Quaterniond quaternion_from_euler(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

std::vector<Eigen::Vector3d> repeat_laps(const std::vector<Eigen::Vector3d>& lap,
                                         const std::vector<Eigen::Vector3d>& connector, int laps) {
  if (laps < 1 || laps > kMaxLaps)
    throw std::invalid_argument("motion.laps: expected an integer in [1, " +
                                std::to_string(kMaxLaps) + "], got " + std::to_string(laps));
  std::vector<Eigen::Vector3d> out;
  out.reserve(lap.size() * laps + connector.size() * (laps - 1));
  for (int k = 0; k < laps; ++k) {
    if (k > 0) out.insert(out.end(), connector.begin(), connector.end());
    out.insert(out.end(), lap.begin(), lap.end());
  }
  return out;
}

PathMotion::PathMotion(SmoothPath path, const MotionOptions& options, uint64_t seed)
    : path_(std::move(path)), options_(options) {
  if (options_.cruise_speed_mps <= 0.0) throw std::invalid_argument("cruise speed must be > 0");
  Rng rng(seed, Stream::kMotion);
  roll_phase_ = rng.uniform(0.0, 2.0 * M_PI);
  pitch_phase_ = rng.uniform(0.0, 2.0 * M_PI);
  heave_phase_ = rng.uniform(0.0, 2.0 * M_PI);
  // Ramps need room: shorten them on short paths.
  options_.ramp_s = std::min(options_.ramp_s, path_.length() / options_.cruise_speed_mps);
  end_time_ = options_.start_rest_s + path_.length() / options_.cruise_speed_mps + options_.ramp_s;
}

void PathMotion::arc_length(double t_s, double* s, double* s_dot, double* s_ddot) const {
  // Quintic smoothstep speed ramp h(x) = 6x^5 - 15x^4 + 10x^3, its integral H and slope h'.
  const double speed = options_.cruise_speed_mps, ramp = options_.ramp_s;
  const double length = path_.length();
  auto h = [](double x) { return x * x * x * (10.0 + x * (-15.0 + 6.0 * x)); };
  auto integral_h = [](double x) { return x * x * x * x * (2.5 + x * (-3.0 + x)); };
  auto slope_h = [](double x) { return 30.0 * x * x * (1.0 - x) * (1.0 - x); };
  const double t = t_s - options_.start_rest_s;
  const double cruise_end = end_time_ - options_.start_rest_s - ramp;
  if (t <= 0.0) {
    *s = 0.0, *s_dot = 0.0, *s_ddot = 0.0;
  } else if (ramp > 0.0 && t < ramp) {
    const double x = t / ramp;
    *s = speed * ramp * integral_h(x), *s_dot = speed * h(x), *s_ddot = speed / ramp * slope_h(x);
  } else if (t < cruise_end) {
    *s = speed * ramp * 0.5 + speed * (t - ramp), *s_dot = speed, *s_ddot = 0.0;
  } else if (ramp > 0.0 && t < cruise_end + ramp) {
    const double x = (cruise_end + ramp - t) / ramp;  // mirrored ramp
    *s = length - speed * ramp * integral_h(x), *s_dot = speed * h(x),
    *s_ddot = -speed / ramp * slope_h(x);
  } else {
    *s = length, *s_dot = 0.0, *s_ddot = 0.0;
  }
}

KinematicState PathMotion::state(double t_s) const {
  double s, s_dot, s_ddot;
  arc_length(t_s, &s, &s_dot, &s_ddot);
  const SmoothPath::Point point = path_.at(s);
  KinematicState out;
  out.t_s = t_s;
  out.path_s = s;
  out.p_world = point.p;
  out.v_world = point.tangent * s_dot;
  out.a_world = point.d2p_ds2 * s_dot * s_dot + point.tangent * s_ddot;

  // Heave adds to z (position, velocity, acceleration of a sinusoid).
  const double wh = 2.0 * M_PI * options_.heave_frequency_hz;
  const double ah = options_.heave_amplitude_m;
  out.p_world.z() += ah * std::sin(wh * t_s + heave_phase_);
  out.v_world.z() += ah * wh * std::cos(wh * t_s + heave_phase_);
  out.a_world.z() += -ah * wh * wh * std::sin(wh * t_s + heave_phase_);

  double yaw = options_.fixed_yaw_rad, yaw_dot = 0.0;
  if (options_.yaw_follows_path) {
    const Eigen::Vector3d& T = point.tangent;
    yaw = std::atan2(T.y(), T.x());
    const double horizontal2 = std::max(T.x() * T.x() + T.y() * T.y(), 1e-12);
    // d/dt atan2(Ty, Tx) = (Tx dTy/ds - Ty dTx/ds) / (Tx^2 + Ty^2) * ds/dt.
    yaw_dot = (T.x() * point.d2p_ds2.y() - T.y() * point.d2p_ds2.x()) / horizontal2 * s_dot;
  }
  const double wr = 2.0 * M_PI * options_.roll_frequency_hz;
  const double wp = 2.0 * M_PI * options_.pitch_frequency_hz;
  const double roll = options_.roll_amplitude_rad * std::sin(wr * t_s + roll_phase_);
  const double roll_dot = options_.roll_amplitude_rad * wr * std::cos(wr * t_s + roll_phase_);
  const double pitch = options_.pitch_amplitude_rad * std::sin(wp * t_s + pitch_phase_);
  const double pitch_dot = options_.pitch_amplitude_rad * wp * std::cos(wp * t_s + pitch_phase_);
  out.q_world_body = quaternion_from_euler(roll, pitch, yaw);
  out.omega_body = euler_rates_to_body_rate(roll, pitch, roll_dot, pitch_dot, yaw_dot);
  return out;
}

}  // namespace keel::sim
