// Beam velocities to the DVL's velocity against the closed forms of a Janus array, and the
// covariance against Monte Carlo.
#include "worker/io/dvl_beams.h"

#include <gtest/gtest.h>
#include <Eigen/LU>

#include <cmath>
#include <random>

namespace keel::io {
namespace {

const double kTilt = kA50BeamTiltDeg * M_PI / 180.0;

std::vector<BeamMeasurement> beams_of(const Eigen::Vector3d& v, std::array<double, 4> noise = {},
                                      std::array<double, 4> sigma = {1, 1, 1, 1}) {
  std::vector<BeamMeasurement> out;
  const auto b = janus_beam_directions(kTilt, {M_PI / 4, 3 * M_PI / 4, 5 * M_PI / 4, 7 * M_PI / 4});
  for (int k = 0; k < 4; ++k) out.push_back({b[k], b[k].dot(v) + noise[k], sigma[k], true});
  return out;
}

TEST(DvlBeams, A50DirectionsAreUnitAndTiltedFromTheAxis) {
  const auto b = a50_beam_directions();
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(b[k].norm(), 1.0, 1e-15);
    EXPECT_NEAR(std::acos(b[k].z()), kTilt, 1e-12);
    EXPECT_NEAR(std::atan2(b[k].y(), b[k].x()),
                std::remainder((135.0 + 90.0 * k) * M_PI / 180.0, 2 * M_PI), 1e-12);
  }
}

// Janus closed form (azimuths 45/135/225/315, tilt t, equal sigma):
//   vx = (r0 - r1 - r2 + r3) / (2 sqrt2 sin t), vy = (r0 + r1 - r2 - r3) / (2 sqrt2 sin t),
//   vz = (r0 + r1 + r2 + r3) / (4 cos t); covariance diag(s^2/(2 sin^2 t), same, s^2/(4 cos^2 t)).
TEST(DvlBeams, FourBeamsGiveTheJanusClosedForm) {
  const Eigen::Vector3d v(0.8, -0.3, 0.12);
  const std::array<double, 4> noise = {0.01, -0.02, 0.005, 0.013};
  const double sigma = 0.02;
  const auto beams = beams_of(v, noise, {sigma, sigma, sigma, sigma});
  std::array<double, 4> r;
  for (int k = 0; k < 4; ++k) r[k] = beams[k].velocity_m_s;
  const double s = std::sin(kTilt), c = std::cos(kTilt);
  const Eigen::Vector3d expected((r[0] - r[1] - r[2] + r[3]) / (2 * std::sqrt(2.0) * s),
                                 (r[0] + r[1] - r[2] - r[3]) / (2 * std::sqrt(2.0) * s),
                                 (r[0] + r[1] + r[2] + r[3]) / (4 * c));
  const BeamSolution solution = solve_beam_velocity(beams);
  ASSERT_TRUE(solution.valid);
  EXPECT_EQ(solution.beams_used, 4);
  EXPECT_LT((solution.velocity_m_s - expected).norm(), 1e-12);
  const Eigen::Vector3d variance(sigma * sigma / (2 * s * s), sigma * sigma / (2 * s * s),
                                 sigma * sigma / (4 * c * c));
  EXPECT_LT((solution.covariance_m2_s2 - Eigen::Matrix3d(variance.asDiagonal())).norm(), 1e-15);
  // Noise-free beams give v itself.
  EXPECT_LT((solve_beam_velocity(beams_of(v)).velocity_m_s - v).norm(), 1e-12);
}

// Three beams determine v exactly: it reproduces the three radial velocities whatever their
// noise; without noise it is v. Beam 3 dropped has the closed form
//   vx = (r0 - r1) / (sqrt2 sin t), vy = (r1 - r2) / (sqrt2 sin t), vz = (r0 + r2) / (2 cos t).
TEST(DvlBeams, ThreeBeamsWhenEachBeamDropsInTurn) {
  const Eigen::Vector3d v(-0.4, 0.9, -0.05);
  const std::array<double, 4> noise = {0.03, -0.01, 0.02, -0.04};
  for (int dropped = 0; dropped < 4; ++dropped) {
    SCOPED_TRACE("dropped beam " + std::to_string(dropped));
    auto exact = beams_of(v);
    exact[dropped].valid = false;
    exact[dropped].velocity_m_s = 99.0;  // a dropped beam's value must not matter
    const BeamSolution clean = solve_beam_velocity(exact);
    ASSERT_TRUE(clean.valid);
    EXPECT_EQ(clean.beams_used, 3);
    EXPECT_LT((clean.velocity_m_s - v).norm(), 1e-12);

    auto noisy = beams_of(v, noise);
    noisy[dropped].valid = false;
    const BeamSolution solution = solve_beam_velocity(noisy);
    ASSERT_TRUE(solution.valid);
    for (int k = 0; k < 4; ++k) {
      if (k == dropped) continue;
      EXPECT_NEAR(noisy[k].direction.dot(solution.velocity_m_s), noisy[k].velocity_m_s, 1e-12);
    }
    // Covariance of an exactly determined system: B^-1 B^-T (unit sigmas).
    Eigen::Matrix3d B;
    for (int k = 0, row = 0; k < 4; ++k)
      if (k != dropped) B.row(row++) = noisy[k].direction.transpose();
    const Eigen::Matrix3d expected = (B.transpose() * B).inverse();
    EXPECT_LT((solution.covariance_m2_s2 - expected).norm(), 1e-9 * expected.norm());
    if (dropped == 3) {
      const double s = std::sin(kTilt), c = std::cos(kTilt);
      const double r0 = noisy[0].velocity_m_s, r1 = noisy[1].velocity_m_s,
                   r2 = noisy[2].velocity_m_s;
      const Eigen::Vector3d closed((r0 - r1) / (std::sqrt(2.0) * s),
                                   (r1 - r2) / (std::sqrt(2.0) * s), (r0 + r2) / (2 * c));
      EXPECT_LT((solution.velocity_m_s - closed).norm(), 1e-12);
    }
  }
}

TEST(DvlBeams, FewerThanThreeBeamsOrCoplanarDirectionsAreInvalid) {
  auto beams = beams_of({0.5, 0.1, 0.0});
  beams[0].valid = false;
  beams[2].valid = false;
  const BeamSolution two = solve_beam_velocity(beams);
  EXPECT_FALSE(two.valid);
  EXPECT_EQ(two.beams_used, 2);
  EXPECT_FALSE(solve_beam_velocity({}).valid);
  // A NaN velocity or a zero sigma counts as a missing beam.
  auto nan = beams_of({0.5, 0.1, 0.0});
  nan[1].velocity_m_s = std::nan("");
  nan[2].sigma_m_s = 0.0;
  EXPECT_FALSE(solve_beam_velocity(nan).valid);
  // Three directions in one plane (all horizontal) leave vz unobserved.
  std::vector<BeamMeasurement> flat;
  for (double a : {0.0, 2.0, 4.0})
    flat.push_back({Eigen::Vector3d(std::cos(a), std::sin(a), 0.0), 0.1, 1.0, true});
  EXPECT_FALSE(solve_beam_velocity(flat).valid);
}

// The covariance (B^T W B)^-1 against the sample covariance of many noisy solutions, with
// unequal beam sigmas (so W matters) and each dropped-beam case.
TEST(DvlBeams, CovarianceMatchesMonteCarlo) {
  const Eigen::Vector3d v(0.3, 0.2, -0.1);
  const std::array<double, 4> sigma = {0.01, 0.02, 0.015, 0.03};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int dropped = -1; dropped < 4; ++dropped) {
    SCOPED_TRACE("dropped beam " + std::to_string(dropped));
    const int n = 40000;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d analytic;
    for (int i = 0; i < n; ++i) {
      std::array<double, 4> noise;
      for (int k = 0; k < 4; ++k) noise[k] = sigma[k] * gauss(rng);
      auto beams = beams_of(v, noise, sigma);
      if (dropped >= 0) beams[dropped].valid = false;
      const BeamSolution s = solve_beam_velocity(beams);
      ASSERT_TRUE(s.valid);
      const Eigen::Vector3d e = s.velocity_m_s - v;
      mean += e;
      second += e * e.transpose();
      analytic = s.covariance_m2_s2;
    }
    mean /= n;
    const Eigen::Matrix3d sample = second / n - mean * mean.transpose();
    // Unbiased: the mean error within 4 standard errors.
    for (int a = 0; a < 3; ++a) EXPECT_LT(std::abs(mean(a)), 4 * std::sqrt(analytic(a, a) / n));
    // Each entry within 5% of the scale of its row and column (the sample covariance of 40000
    // draws is within ~1.5% at 2 sigma).
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        EXPECT_NEAR(sample(a, b), analytic(a, b), 0.05 * std::sqrt(analytic(a, a) * analytic(b, b)))
            << "entry " << a << "," << b;
  }
}

}  // namespace
}  // namespace keel::io
