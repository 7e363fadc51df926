// Forster et al. preintegration: bias Jacobians against re-integration (first-order check, as
// GTSAM's navigation tests do) and the propagated covariance against Monte Carlo.
#include "worker/slam/imu_preintegration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

struct Sample {
  Eigen::Vector3d gyro, accel;
};

std::vector<Sample> motion(int n, double dt) {
  std::vector<Sample> s;
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    s.push_back({Eigen::Vector3d(0.3 * std::sin(2 * t), -0.2 + 0.1 * std::cos(3 * t), 0.5),
                 Eigen::Vector3d(0.5 * std::cos(t), 0.3 * std::sin(2 * t), 9.81 + 0.2 * t)});
  }
  return s;
}

ImuPreintegration integrate(const std::vector<Sample>& s, double dt, const Eigen::Vector3d& bg,
                            const Eigen::Vector3d& ba) {
  ImuPreintegration pre(bg, ba, ImuNoise{});
  for (const Sample& m : s) pre.integrate(m.gyro, m.accel, dt);
  return pre;
}

TEST(ImuPreintegration, ConstantRatesMatchClosedForm) {
  // Pure rotation about z at 0.5 rad/s and constant specific force along x: Delta R =
  // Exp(w t), Delta v = sum_k Rz(k w dt) a dt.
  const double dt = 0.005;
  ImuPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise{});
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < 200; ++k) {
    pre.integrate(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(1, 0, 0), dt);
    v += so3_exp(Eigen::Vector3d(0, 0, 0.5 * k * dt)) * Eigen::Vector3d(dt, 0, 0);
  }
  EXPECT_LT((pre.delta_R() - so3_exp(Eigen::Vector3d(0, 0, 0.5))).norm(), 1e-12);
  EXPECT_LT((pre.delta_v() - v).norm(), 1e-12);
  EXPECT_NEAR(pre.dt_s(), 1.0, 1e-12);
}

TEST(ImuPreintegration, BiasJacobiansMatchReintegration) {
  const double dt = 0.005;
  const auto s = motion(300, dt);
  const Eigen::Vector3d bg(0.01, -0.02, 0.005), ba(0.1, 0.05, -0.08);
  const ImuPreintegration pre = integrate(s, dt, bg, ba);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) * h;
    const ImuPreintegration gp = integrate(s, dt, bg + e, ba), gm = integrate(s, dt, bg - e, ba);
    const ImuPreintegration ap = integrate(s, dt, bg, ba + e), am = integrate(s, dt, bg, ba - e);
    const Eigen::Vector3d dR = so3_log(gm.delta_R().transpose() * gp.delta_R()) / (2 * h);
    EXPECT_LT((dR - pre.dR_dbg().col(k)).norm(), 1e-6);
    EXPECT_LT(((gp.delta_v() - gm.delta_v()) / (2 * h) - pre.dv_dbg().col(k)).norm(), 1e-6);
    EXPECT_LT(((gp.delta_p() - gm.delta_p()) / (2 * h) - pre.dp_dbg().col(k)).norm(), 1e-6);
    EXPECT_LT(((ap.delta_v() - am.delta_v()) / (2 * h) - pre.dv_dba().col(k)).norm(), 1e-6);
    EXPECT_LT(((ap.delta_p() - am.delta_p()) / (2 * h) - pre.dp_dba().col(k)).norm(), 1e-6);
  }
  // First-order correction (Forster Eq. (44)): error is second order in the bias change.
  const Eigen::Vector3d dbg(2e-3, -1e-3, 3e-3), dba(0.02, -0.03, 0.01);
  const ImuPreintegration re = integrate(s, dt, bg + dbg, ba + dba);
  const Eigen::Vector3d dp_change = re.delta_p() - pre.delta_p();
  const Eigen::Vector3d dp_error = pre.corrected_delta_p(bg + dbg, ba + dba) - re.delta_p();
  EXPECT_LT(dp_error.norm(), 1e-2 * dp_change.norm());
  EXPECT_LT((pre.corrected_delta_v(bg + dbg, ba + dba) - re.delta_v()).norm(),
            1e-2 * (re.delta_v() - pre.delta_v()).norm());
  EXPECT_LT(so3_log(pre.corrected_delta_R(bg + dbg).transpose() * re.delta_R()).norm(),
            1e-2 * so3_log(pre.delta_R().transpose() * re.delta_R()).norm());
}

TEST(ImuPreintegration, CovarianceMatchesMonteCarlo) {
  const double dt = 0.005;
  const int steps = 100;
  const auto s = motion(steps, dt);
  const ImuNoise noise;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const ImuPreintegration truth = integrate(s, dt, zero, zero);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> ng(0.0, noise.gyro_noise_density / std::sqrt(dt));
  std::normal_distribution<double> na(0.0, noise.accel_noise_density / std::sqrt(dt));
  const int runs = 2000;
  Eigen::Matrix<double, 9, 9> mc = Eigen::Matrix<double, 9, 9>::Zero();
  for (int r = 0; r < runs; ++r) {
    ImuPreintegration pre(zero, zero, noise);
    for (const Sample& m : s) {
      pre.integrate(m.gyro + Eigen::Vector3d(ng(rng), ng(rng), ng(rng)),
                    m.accel + Eigen::Vector3d(na(rng), na(rng), na(rng)), dt);
    }
    // Noise definitions of Forster Eq. (38): Delta R~ = Delta R Exp(delta phi), etc.
    Eigen::Matrix<double, 9, 1> e;
    e << so3_log(truth.delta_R().transpose() * pre.delta_R()), pre.delta_v() - truth.delta_v(),
        pre.delta_p() - truth.delta_p();
    mc += e * e.transpose() / runs;
  }
  const Eigen::Matrix<double, 9, 9>& cov = truth.covariance();
  EXPECT_LT((mc - cov).norm(), 0.1 * cov.norm());
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(mc(k, k), cov(k, k), 0.1 * cov(k, k)) << k;
}

}  // namespace
}  // namespace keel::slam
