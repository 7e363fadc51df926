#include "tests/sim/inertial_sensors.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/sim/scenarios.h"

namespace keel::sim {
namespace {

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double a = w.norm();
  return a < 1e-15 ? Eigen::Matrix3d::Identity() : Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

TEST(Imu, SpecificForceAtRestIsPlusGOnZ) {
  ScenarioOptions options;
  options.motion.roll_amplitude_rad = options.motion.pitch_amplitude_rad = 0.0;
  options.motion.heave_amplitude_m = 0.0;
  const Scenario s = make_scenario("usv-corridor", 1, options);
  const Eigen::Vector3d f = specific_force(s.motion->state(0.5));  // resting at the start
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 0.0, 1e-12);
  EXPECT_NEAR(f.z(), 9.81, 1e-12);
}

// Strapdown integration (midpoint rotation, trapezoidal velocity) of noise-free samples must
// reproduce the true trajectory: validates body-frame rates and the specific-force sign.
TEST(Imu, NoiseFreeSamplesIntegrateToTheTrajectory) {
  for (const char* name : {"usv-bridge", "hauv-hull"}) {
    const Scenario s = make_scenario(name, 5);
    ImuOptions options;
    options.noise = false;
    const double t_start = 20.0, span = 10.0;
    const auto samples = simulate_imu(*s.motion, t_start + span, options, 5);
    const Eigen::Vector3d g(0, 0, -kGravity);
    size_t k = static_cast<size_t>(t_start * options.rate_hz);
    KinematicState init = s.motion->state(samples[k].t_ns * 1e-9);
    Eigen::Matrix3d R = init.q_world_body.toRotationMatrix();
    Eigen::Vector3d v = init.v_world, p = init.p_world;
    for (; k + 1 < samples.size(); ++k) {
      const double dt = (samples[k + 1].t_ns - samples[k].t_ns) * 1e-9;
      const Eigen::Matrix3d R_next =
          R * exp_so3(0.5 * (samples[k].gyro + samples[k + 1].gyro) * dt);
      const Eigen::Vector3d a0 = R * samples[k].accel + g, a1 = R_next * samples[k + 1].accel + g;
      p += v * dt + (2.0 * a0 + a1) / 6.0 * dt * dt;
      v += 0.5 * (a0 + a1) * dt;
      R = R_next;
    }
    const KinematicState end = s.motion->state(samples.back().t_ns * 1e-9);
    EXPECT_LT((p - end.p_world).norm(), 0.01) << name;
    EXPECT_LT((v - end.v_world).norm(), 0.002) << name;
    EXPECT_LT(Eigen::AngleAxisd(end.q_world_body.toRotationMatrix().transpose() * R).angle(), 1e-4)
        << name;
  }
}

// Discrete-time white noise sigma = density * sqrt(rate) (seed 000 Table I).
TEST(Imu, NoiseStdMatchesDensityTimesSqrtRate) {
  const Scenario s = make_scenario("usv-bridge", 9);
  ImuOptions noisy, clean;
  clean.noise = false;
  const double duration = 100.0;
  const auto a = simulate_imu(*s.motion, duration, noisy, 9);
  const auto b = simulate_imu(*s.motion, duration, clean, 9);
  ASSERT_EQ(a.size(), b.size());
  for (int axis = 0; axis < 3; ++axis) {
    double sg = 0, sg2 = 0, sa = 0, sa2 = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      const double eg = a[i].gyro[axis] - b[i].gyro[axis] - a[i].gyro_bias[axis];
      const double ea = a[i].accel[axis] - b[i].accel[axis] - a[i].accel_bias[axis];
      sg += eg, sg2 += eg * eg, sa += ea, sa2 += ea * ea;
    }
    const double n = static_cast<double>(a.size());
    const double std_g = std::sqrt(sg2 / n - (sg / n) * (sg / n));
    const double std_a = std::sqrt(sa2 / n - (sa / n) * (sa / n));
    EXPECT_NEAR(std_g / (noisy.gyro_noise_density * std::sqrt(noisy.rate_hz)), 1.0, 0.05);
    EXPECT_NEAR(std_a / (noisy.accel_noise_density * std::sqrt(noisy.rate_hz)), 1.0, 0.05);
  }
}

// Noise-free DVL = s_d * R_dvl_body (R_wb^T v_w + w x t_body_dvl); checked against the
// numerically differentiated world position of the DVL origin.
TEST(Dvl, NoiseFreeVelocityIsScaledVelocityOfTheDvlOrigin) {
  for (const char* name : {"usv-bridge", "hauv-hull"}) {
    const Scenario s = make_scenario(name, 2);
    DvlOptions options;
    options.noise = false;
    options.scale = 1.02;
    auto T_body_dvl = [&](double t) { return s.T_body_sensor_at("dvl", t); };
    const auto samples = simulate_dvl(*s.motion, 60.0, T_body_dvl, options, 2);
    const double h = 1e-4;
    for (size_t i = 100; i < samples.size(); i += 97) {
      const double t = samples[i].t_ns * 1e-9;
      auto origin = [&](double tt) {
        const KinematicState st = s.motion->state(tt);
        return Eigen::Vector3d(st.p_world + st.q_world_body * T_body_dvl(t).translation());
      };
      const KinematicState st = s.motion->state(t);
      const Eigen::Matrix3d R_world_dvl =
          st.q_world_body.toRotationMatrix() * T_body_dvl(t).linear();
      const Eigen::Vector3d expected =
          1.02 * R_world_dvl.transpose() * (origin(t + h) - origin(t - h)) / (2 * h);
      EXPECT_LT((samples[i].velocity - expected).norm(), 1e-6) << name << " t=" << t;
      EXPECT_TRUE(samples[i].valid);
    }
  }
}

TEST(Dvl, DropoutFractionMatchesTheRate) {
  const Scenario s = make_scenario("usv-bridge", 4);
  DvlOptions options;
  options.dropout_rate = 0.2;
  const auto samples = simulate_dvl(
      *s.motion, 220.0, [&](double) { return s.T_body_sensor.at("dvl"); }, options, 4);
  size_t lost = 0;
  for (const auto& x : samples) lost += !x.valid;
  EXPECT_NEAR(double(lost) / samples.size(), 0.2, 0.06);
}

TEST(Servo, MeasurementNoiseIsFiveDegrees) {
  const auto samples = simulate_servo([](double t) { return 0.3 * std::sin(t); }, 500.0, 20.0,
                                      5.0 * M_PI / 180.0, 3);
  double sum2 = 0;
  for (const auto& x : samples) sum2 += (x.value - x.value_true) * (x.value - x.value_true);
  EXPECT_NEAR(std::sqrt(sum2 / samples.size()) / (5.0 * M_PI / 180.0), 1.0, 0.05);
}

}  // namespace
}  // namespace keel::sim
