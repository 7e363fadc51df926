#include "tests/sim/inertial_sensors.h"

#include <cmath>

#include "tests/sim/rng.h"

namespace keel::sim {

std::vector<int64_t> sample_times_ns(double rate_hz, double duration_s) {
  std::vector<int64_t> out;
  const double period_ns = 1e9 / rate_hz;
  const int64_t end_ns = std::llround(duration_s * 1e9);
  for (int64_t k = 0;; ++k) {
    const int64_t t = std::llround(k * period_ns);
    if (t > end_ns) break;
    out.push_back(t);
  }
  return out;
}

Eigen::Vector3d specific_force(const KinematicState& s) {
  const Eigen::Vector3d g_world(0.0, 0.0, -kGravity);
  return s.q_world_body.conjugate() * (s.a_world - g_world);
}

std::vector<ImuSample> simulate_imu(const PathMotion& motion, double duration_s,
                                    const ImuOptions& o, uint64_t seed) {
  Rng rng(seed, Stream::kImu);
  const double dt = 1.0 / o.rate_hz;
  const double sigma_g = o.gyro_noise_density * std::sqrt(o.rate_hz);
  const double sigma_a = o.accel_noise_density * std::sqrt(o.rate_hz);
  const double walk_g = o.gyro_random_walk * std::sqrt(dt);
  const double walk_a = o.accel_random_walk * std::sqrt(dt);
  auto gaussian3 = [&rng] {
    return Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian());
  };
  Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
  if (o.noise) {  // turn-on biases, small (a calibrated unit)
    bg = 2e-4 * gaussian3();
    ba = 5e-3 * gaussian3();
  }
  std::vector<ImuSample> out;
  for (int64_t t_ns : sample_times_ns(o.rate_hz, duration_s)) {
    const KinematicState s = motion.state(t_ns * 1e-9);
    ImuSample sample{t_ns, s.omega_body, specific_force(s), bg, ba};
    if (o.noise) {
      sample.gyro += bg + sigma_g * gaussian3();   // Eq. (4)
      sample.accel += ba + sigma_a * gaussian3();  // Eq. (5)
      bg += walk_g * gaussian3();                  // Eq. (7)
      ba += walk_a * gaussian3();
    }
    out.push_back(sample);
  }
  return out;
}

Eigen::Vector3d dvl_velocity(const KinematicState& s, const Pose3& T_body_dvl) {
  const Eigen::Vector3d v_body = s.q_world_body.conjugate() * s.v_world;
  return T_body_dvl.linear().transpose() *
         (v_body + s.omega_body.cross(Eigen::Vector3d(T_body_dvl.translation())));
}

std::vector<DvlSample> simulate_dvl(const PathMotion& motion, double duration_s,
                                    const std::function<Pose3(double)>& T_body_dvl,
                                    const DvlOptions& o, uint64_t seed,
                                    const std::function<bool(double, const Pose3&)>& has_lock) {
  Rng rng(seed, Stream::kDvl);
  Rng dropout_rng(seed, Stream::kDropout);
  const double dt = 1.0 / o.rate_hz;
  // Two-state Markov chain: leave a dropout with p_exit per sample, enter with p_enter so
  // that the stationary lost fraction is dropout_rate.
  const double p_exit = std::min(1.0, dt / std::max(o.dropout_mean_length_s, dt));
  const double rate = std::clamp(o.dropout_rate, 0.0, 0.95);
  const double p_enter = rate > 0.0 ? rate * p_exit / (1.0 - rate) : 0.0;
  bool in_dropout = false;
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  std::vector<DvlSample> out;
  for (int64_t t_ns : sample_times_ns(o.rate_hz, duration_s)) {
    const double t = t_ns * 1e-9;
    const KinematicState s = motion.state(t);
    const Pose3 T = T_body_dvl(t);
    DvlSample sample;
    sample.t_ns = t_ns;
    sample.velocity_true = dvl_velocity(s, T);
    const double speed = sample.velocity_true.norm();
    const Eigen::Vector3d noise(rng.gaussian(), rng.gaussian(), rng.gaussian());
    const Eigen::Vector3d walk(rng.gaussian(), rng.gaussian(), rng.gaussian());
    sample.velocity = o.scale * sample.velocity_true;  // Eq. (10)
    if (o.noise) {
      sample.velocity += bias + o.velocity_sigma_rel * speed * noise;
      bias += o.bias_random_walk_rel * speed * std::sqrt(dt) * walk;
    }
    const double u = dropout_rng.uniform();
    in_dropout = in_dropout ? u >= p_exit : u < p_enter;
    sample.valid = !in_dropout && (!has_lock || has_lock(t, T));
    out.push_back(sample);
  }
  return out;
}

std::array<Eigen::Vector3d, 4> janus_beams(double angle_deg) {
  const double a = angle_deg * M_PI / 180.0, s = std::sin(a), c = std::cos(a);
  return {Eigen::Vector3d(s, 0, c), Eigen::Vector3d(-s, 0, c), Eigen::Vector3d(0, s, c),
          Eigen::Vector3d(0, -s, c)};
}

std::vector<ScalarSample> simulate_depth(const PathMotion& motion, double duration_s,
                                         const Eigen::Vector3d& t_body_sensor, double rate_hz,
                                         double sigma_m, uint64_t seed) {
  Rng rng(seed, Stream::kDepth);
  std::vector<ScalarSample> out;
  for (int64_t t_ns : sample_times_ns(rate_hz, duration_s)) {
    const KinematicState s = motion.state(t_ns * 1e-9);
    const double depth = -(s.p_world + s.q_world_body * t_body_sensor).z();
    out.push_back({t_ns, depth + sigma_m * rng.gaussian(), depth});
  }
  return out;
}

std::vector<ScalarSample> simulate_servo(const std::function<double(double)>& angle_true,
                                         double duration_s, double rate_hz, double sigma_rad,
                                         uint64_t seed) {
  Rng rng(seed, Stream::kServo);
  std::vector<ScalarSample> out;
  for (int64_t t_ns : sample_times_ns(rate_hz, duration_s)) {
    const double angle = angle_true(t_ns * 1e-9);
    out.push_back({t_ns, angle + sigma_rad * rng.gaussian(), angle});
  }
  return out;
}

}  // namespace keel::sim
