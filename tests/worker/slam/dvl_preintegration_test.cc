// DVL preintegration, seed 000 Eq. (11)-(16), (27)-(32): closed forms, bias/scale/extrinsic
// corrections against re-integration, covariance against Monte Carlo.
#include "worker/slam/dvl_preintegration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "worker/slam/dvl_imu_reconciliation.h"
#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

struct Pseudo {
  Eigen::Vector3d gyro, v_dvl;
};

std::vector<Pseudo> motion(int n, double dt) {
  std::vector<Pseudo> s;
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    s.push_back({Eigen::Vector3d(0.05 * std::sin(2 * t), -0.03 * std::cos(t), 0.2 + 0.1 * t),
                 Eigen::Vector3d(1.2 + 0.2 * std::sin(t), 0.1 * std::cos(3 * t), 0.05)});
  }
  return s;
}

struct Lin {
  Eigen::Vector3d bg = Eigen::Vector3d(0.003, -0.002, 0.004);
  Eigen::Vector3d bv = Eigen::Vector3d(0.01, -0.02, 0.005);
  double s = 1.03;
  Eigen::Matrix3d R = so3_exp(Eigen::Vector3d(0.01, -0.02, 0.3));
};

DvlPreintegration integrate(const std::vector<Pseudo>& s, double dt, const Lin& lin) {
  DvlPreintegration pre(lin.bg, lin.bv, lin.s, lin.R, DvlNoise{}, 5.7e-4);
  for (const Pseudo& m : s) pre.integrate(m.gyro, m.v_dvl, dt, 0.05);
  return pre;
}

TEST(DvlPreintegration, CircularArcMatchesClosedForm) {
  // Constant body velocity v with constant yaw rate w: Eq. (11) is the geometric sum
  // sum_k Rz(k w dt) v dt, whose closed form is sum_k e^{i k theta} = (1 - e^{iN theta}) /
  // (1 - e^{i theta}); as dt -> 0 it tends to the arc integral of Rz(w t) v.
  const double w = 0.2, dt = 0.005, T = 5.0;
  const int N = static_cast<int>(std::lround(T / dt));
  const Eigen::Vector3d v(1.2, 0.1, 0.05);
  const double s_d = 1.02;
  const Eigen::Vector3d b(0.01, -0.02, 0.0);
  DvlPreintegration pre(Eigen::Vector3d::Zero(), b, s_d, Eigen::Matrix3d::Identity(), DvlNoise{},
                        5.7e-4);
  for (int k = 0; k < N; ++k) pre.integrate(Eigen::Vector3d(0, 0, w), s_d * v + b, dt, 0.05);

  const std::complex<double> z = std::polar(1.0, w * dt);
  const std::complex<double> sum = (1.0 - std::pow(z, N)) / (1.0 - z);
  Eigen::Matrix3d M;
  M << sum.real(), -sum.imag(), 0, sum.imag(), sum.real(), 0, 0, 0, N;
  const Eigen::Vector3d discrete = M * v * dt;
  EXPECT_LT((pre.delta_p() - discrete).norm(), 1e-10);

  Eigen::Matrix3d A;
  A << std::sin(w * T) / w, -(1 - std::cos(w * T)) / w, 0, (1 - std::cos(w * T)) / w,
      std::sin(w * T) / w, 0, 0, 0, T;
  const Eigen::Vector3d arc = A * v;
  // Left Riemann sum: error ~ dt/2 |v(T) - v(0)| <= dt |v|.
  EXPECT_LT((pre.delta_p() - arc).norm(), dt * v.norm());
  EXPECT_LT((pre.delta_R() - so3_exp(Eigen::Vector3d(0, 0, w * T))).norm(), 1e-12);
}

TEST(DvlPreintegration, JacobiansMatchReintegration) {
  const double dt = 0.005;
  const auto s = motion(400, dt);
  const Lin lin;
  const DvlPreintegration pre = integrate(s, dt, lin);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k) * h;
    Lin gp = lin, gm = lin, vp = lin, vm = lin, rp = lin, rm = lin;
    gp.bg += e;
    gm.bg -= e;
    vp.bv += e;
    vm.bv -= e;
    rp.R = lin.R * so3_exp(e);
    rm.R = lin.R * so3_exp(-e);
    auto d = [&](const Lin& a, const Lin& b) {
      return Eigen::Vector3d((integrate(s, dt, a).delta_p() - integrate(s, dt, b).delta_p()) /
                             (2 * h));
    };
    EXPECT_LT((d(gp, gm) - pre.dp_dbg().col(k)).norm(), 1e-6) << "Eq. (28), column " << k;
    EXPECT_LT((d(vp, vm) - pre.dp_dbv().col(k)).norm(), 1e-6) << "Eq. (29), column " << k;
    EXPECT_LT((d(rp, rm) - pre.dp_dtheta().col(k)).norm(), 1e-6) << "extrinsic, column " << k;
  }
}

TEST(DvlPreintegration, FirstOrderBiasCorrectionTracksReintegration) {
  // Appendix A, Eq. (27): perturb the biases, compare the corrected Delta p~ with the one
  // recomputed from scratch; the residual error must be second order.
  const double dt = 0.005;
  const auto s = motion(400, dt);
  const Lin lin;
  const DvlPreintegration pre = integrate(s, dt, lin);
  Lin moved = lin;
  moved.bg += Eigen::Vector3d(2e-3, -3e-3, 1e-3);
  moved.bv += Eigen::Vector3d(0.01, 0.02, -0.01);
  moved.R = lin.R * so3_exp(Eigen::Vector3d(0.005, -0.004, 0.01));
  const DvlPreintegration re = integrate(s, dt, moved);
  const Eigen::Vector3d corrected = pre.corrected_delta_p(moved.bg, moved.bv, lin.s, moved.R);
  const double change = (re.delta_p() - pre.delta_p()).norm();
  ASSERT_GT(change, 1e-3);
  EXPECT_LT((corrected - re.delta_p()).norm(), 1e-2 * change);
}

TEST(DvlPreintegration, ScaleDependenceIsExact) {
  const double dt = 0.005;
  const auto s = motion(200, dt);
  const Lin lin;
  Lin scaled = lin;
  scaled.s = 0.97;
  const DvlPreintegration pre = integrate(s, dt, lin);
  const DvlPreintegration re = integrate(s, dt, scaled);
  EXPECT_LT((pre.corrected_delta_p(lin.bg, lin.bv, 0.97, lin.R) - re.delta_p()).norm(), 1e-12);
}

// Eq. (16) with A, B of Eq. (31)-(32) against the spread of Delta p~ and Delta R~ when white
// noise of the modelled covariance is added to the gyro and the pseudo velocities.
TEST(DvlPreintegration, CovarianceMatchesMonteCarlo) {
  const double dt = 0.005, dvl_period = 0.05;
  const int steps = 200;
  const auto s = motion(steps, dt);
  Lin lin;
  DvlNoise noise;
  noise.velocity_sigma_floor_mps = 0.02;  // larger noise, same model: a well-resolved spread
  const double gyro_density = 5.7e-4;
  DvlPreintegration truth(lin.bg, lin.bv, lin.s, lin.R, noise, gyro_density);
  for (const Pseudo& m : s) truth.integrate(m.gyro, m.v_dvl, dt, dvl_period);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int runs = 2000;
  Eigen::Matrix<double, 6, 6> mc = Eigen::Matrix<double, 6, 6>::Zero();
  for (int r = 0; r < runs; ++r) {
    DvlPreintegration pre(lin.bg, lin.bv, lin.s, lin.R, noise, gyro_density);
    for (const Pseudo& m : s) {
      const double sg = gyro_density / std::sqrt(dt);
      const double sv = noise.velocity_sigma(m.v_dvl.norm()) * std::sqrt(dvl_period / dt);
      const Eigen::Vector3d eg(n01(rng), n01(rng), n01(rng)), ev(n01(rng), n01(rng), n01(rng));
      // eta^v is defined in B (Eq. (10) after rotation); rotate it back into B_o to add it.
      pre.integrate(m.gyro + sg * eg, m.v_dvl + lin.R.transpose() * (sv * ev), dt, dvl_period);
    }
    Eigen::Matrix<double, 6, 1> e;
    e << so3_log(truth.delta_R().transpose() * pre.delta_R()), pre.delta_p() - truth.delta_p();
    mc += e * e.transpose() / runs;
  }
  const Eigen::Matrix<double, 6, 6>& cov = truth.covariance();
  EXPECT_LT((mc - cov).norm(), 0.1 * cov.norm());
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(mc(k, k), cov(k, k), 0.1 * cov(k, k)) << k;
}

// The DVL-rate noise model: white noise on the 20 Hz DVL samples, interpolated by Algorithm 1
// and preintegrated at 200 Hz, spreads Delta p~ as the covariance predicts.
TEST(DvlPreintegration, DvlRateNoiseThroughAlgorithm1MatchesCovariance) {
  const double T = 2.0, imu_dt = 0.005, dvl_dt = 0.05;
  DvlNoise noise;
  noise.velocity_sigma_rel = 0.0;
  noise.velocity_sigma_floor_mps = 0.01;
  std::vector<ImuSample> imu;
  for (int k = 0; k <= static_cast<int>(T / imu_dt); ++k) {
    ImuSample m;
    m.t_ns = seconds_to_ns(k * imu_dt);
    m.gyro_radps = Eigen::Vector3d(0, 0, 0.3);
    imu.push_back(m);
  }
  std::mt19937_64 rng(11);
  std::normal_distribution<double> nv(0.0, noise.velocity_sigma_floor_mps);
  const int runs = 2000;
  Eigen::Matrix3d mc = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d predicted = Eigen::Matrix3d::Zero();
  Eigen::Vector3d mean_truth = Eigen::Vector3d::Zero();
  for (int r = -1; r < runs; ++r) {  // r = -1: the noise-free reference
    std::vector<DvlSample> dvl;
    for (int l = 0; l <= static_cast<int>(T / dvl_dt); ++l) {
      DvlSample d;
      d.t_ns = seconds_to_ns(l * dvl_dt);
      d.velocity_mps = Eigen::Vector3d(1.0, 0.2, 0.0);
      if (r >= 0) d.velocity_mps += Eigen::Vector3d(nv(rng), nv(rng), nv(rng));
      dvl.push_back(d);
    }
    const auto pseudo = reconcile_dvl_imu(dvl, imu, Eigen::Matrix3d::Identity());
    DvlPreintegration pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0,
                          Eigen::Matrix3d::Identity(), noise, 0.0);
    ASSERT_TRUE(for_each_hold_segment(
        pseudo, 0, seconds_to_ns(T), seconds_to_ns(0.1), [&](const PseudoSample& p, double dt) {
          pre.integrate(p.gyro_radps, p.velocity_dvl_mps, dt, p.dvl_period_s);
        }));
    if (r < 0) {
      predicted = pre.position_covariance();
      mean_truth = pre.delta_p();
      continue;
    }
    const Eigen::Vector3d e = pre.delta_p() - mean_truth;
    mc += e * e.transpose() / runs;
  }
  EXPECT_NEAR(mc.trace(), predicted.trace(), 0.1 * predicted.trace());
  EXPECT_LT((mc - predicted).norm(), 0.1 * predicted.norm());
}

}  // namespace
}  // namespace keel::slam
