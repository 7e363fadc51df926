// Odometry noise from the MAP poses against closed forms and brute force: the disagreement RMS
// of increments perturbed by chosen amounts, and the widened information against the inverse
// of Sigma + diag(sigma^2) computed directly (through a regularised inverse where the
// information is singular).
#include "worker/slam/odometry_noise_from_map.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

// Keyframes along a curve that turns about every axis, 1 s apart.
Trajectory keyframes(int n) {
  Trajectory t;
  for (int k = 0; k < n; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(1.1 * k, 0.3 * k * k, -0.2 * k);
    T.linear() = so3_exp(Eigen::Vector3d(0.05 * k, -0.02 * k, 0.3 * k));
    t.push_back({TimeNs(k) * 1000000000, T});
  }
  return t;
}

// The edge k -> k+1 of `map` with translation error e_t (frame of keyframe k) and rotation
// error e_r (R_odo = R_map Exp(e_r)).
RelativePoseMeasurement edge(const Trajectory& map, size_t k, const Eigen::Vector3d& e_t,
                             const Eigen::Vector3d& e_r) {
  RelativePoseMeasurement m;
  m.t_i_ns = map[k].t_ns;
  m.t_j_ns = map[k + 1].t_ns;
  m.T_i_j = map[k].T_world_body.inverse() * map[k + 1].T_world_body;
  m.T_i_j.translation() += e_t;
  m.T_i_j.linear() = m.T_i_j.linear() * so3_exp(e_r);
  m.information = isotropic_information(0.02, 0.002);
  return m;
}

Matrix6d random_information(unsigned seed) {
  std::srand(seed);
  const Matrix6d A = Matrix6d::Random();
  return A * A.transpose() + 0.1 * Matrix6d::Identity();
}

TEST(IsotropicInformation, InverseSquaredSigmasOnTheDiagonal) {
  const Matrix6d info = isotropic_information(0.5, 0.01);
  Matrix6d expected = Matrix6d::Zero();
  expected.diagonal() << 4.0, 4.0, 4.0, 1e4, 1e4, 1e4;
  EXPECT_TRUE(info.isApprox(expected, 1e-12)) << info;
}

TEST(OdometryDisagreement, RmsPerAxisOfChosenErrors) {
  const Trajectory map = keyframes(4);
  std::vector<RelativePoseMeasurement> odometry = {
      edge(map, 0, {0.1, 0.0, 0.0}, {0.0, 0.0, 0.01}),
      edge(map, 1, {-0.1, 0.2, 0.0}, {0.0, 0.0, 0.0}),
      edge(map, 2, {0.0, 0.0, 0.0}, {0.0, 0.02, -0.01}),
  };
  const std::optional<Vector6d> rms = odometry_disagreement_rms(map, odometry);
  ASSERT_TRUE(rms);
  Vector6d expected;
  expected << std::sqrt(0.02 / 3.0), std::sqrt(0.04 / 3.0), 0.0, 0.0, std::sqrt(0.0004 / 3.0),
      std::sqrt(0.0002 / 3.0);
  EXPECT_TRUE(rms->isApprox(expected, 1e-9)) << rms->transpose();

  // An edge without information (a failed registration) is not averaged over.
  odometry[2].information.setZero();
  const std::optional<Vector6d> two = odometry_disagreement_rms(map, odometry);
  ASSERT_TRUE(two);
  EXPECT_NEAR((*two)[0], std::sqrt(0.02 / 2.0), 1e-12);
  EXPECT_NEAR((*two)[4], 0.0, 1e-12);
  EXPECT_NEAR((*two)[5], std::sqrt(0.0001 / 2.0), 1e-12);
}

TEST(OdometryDisagreement, NoneWithoutOneEdgePerKeyframePairOrWithoutInformation) {
  const Trajectory map = keyframes(3);
  std::vector<RelativePoseMeasurement> one = {edge(map, 0, {0.1, 0, 0}, {0, 0, 0})};
  EXPECT_FALSE(odometry_disagreement_rms(map, one));
  std::vector<RelativePoseMeasurement> blind = {edge(map, 0, {0.1, 0, 0}, {0, 0, 0}),
                                                edge(map, 1, {0.1, 0, 0}, {0, 0, 0})};
  for (auto& e : blind) e.information.setZero();
  EXPECT_FALSE(odometry_disagreement_rms(map, blind));
  EXPECT_FALSE(widen_by_map_disagreement(map, one));
  EXPECT_TRUE(one[0].information.isApprox(isotropic_information(0.02, 0.002)));
}

TEST(WidenInformation, DiagonalIsOneOverTheSumOfVariances) {
  const Matrix6d info = isotropic_information(0.02, 0.002);
  Vector6d sigma;
  sigma << 0.03, 0.0, 0.1, 0.001, 0.004, 0.0;
  const Matrix6d widened = widen_information(info, sigma);
  for (int a = 0; a < 6; ++a) {
    const double s = a < 3 ? 0.02 : 0.002;
    const double added = std::max(sigma[a], 1e-6);  // the floor
    EXPECT_NEAR(widened(a, a) * (s * s + added * added), 1.0, 1e-9) << a;
  }
  EXPECT_TRUE(widened.isDiagonal(1e-9));
}

TEST(WidenInformation, FullInformationMatchesTheInverseOfTheSummedCovariance) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Matrix6d info = random_information(seed);
    Vector6d sigma;
    sigma << 0.05, 0.2, 0.01, 0.003, 0.1, 0.02;
    const Matrix6d direct =
        (info.inverse() + Matrix6d(sigma.cwiseProduct(sigma).asDiagonal())).inverse();
    const Matrix6d widened = widen_information(info, sigma);
    EXPECT_TRUE(widened.isApprox(direct, 1e-9)) << seed;
    EXPECT_TRUE(widened.isApprox(widened.transpose(), 0.0)) << seed;
  }
}

TEST(WidenInformation, SingularInformationKeepsItsNullSpaceAndCorrelations) {
  // Rank 4: nothing about pitch, nor along (y, roll) = (-5, 10), while (10, 5) is observed: y
  // and roll coupled as through a lidar's lever arm.
  Eigen::Matrix<double, 6, 4> B = Eigen::Matrix<double, 6, 4>::Zero();
  B(0, 0) = 30.0;
  B(2, 1) = 20.0;
  B(1, 2) = 10.0;
  B(3, 2) = 5.0;
  B(5, 3) = 300.0;
  const Matrix6d info = B * B.transpose();
  Vector6d sigma;
  sigma << 0.05, 0.05, 0.05, 0.01, 0.01, 0.01;
  const Matrix6d widened = widen_information(info, sigma);
  // The limit of the regularised inverse: information + eps I stands for a covariance that is
  // 1/eps along the null space.
  const double eps = 1e-6;
  const Matrix6d direct = ((info + eps * Matrix6d::Identity()).inverse() +
                           Matrix6d(sigma.cwiseProduct(sigma).asDiagonal()))
                              .inverse();
  EXPECT_TRUE(widened.isApprox(direct, 1e-6)) << widened << "\n\n" << direct;
  Vector6d pitch = Vector6d::Zero(), y_roll = Vector6d::Zero();
  pitch[4] = 1.0;
  y_roll[1] = -5.0;
  y_roll[3] = 10.0;
  EXPECT_NEAR((widened * pitch).norm(), 0.0, 1e-9);  // no information before, none after
  EXPECT_NEAR((widened * y_roll).norm(), 0.0, 1e-9);
  EXPECT_GT(std::abs(widened(1, 3)), 1e-3);  // the y-roll correlation survives
}

TEST(WidenByMapDisagreement, WidensEveryEdgeByTheRms) {
  const Trajectory map = keyframes(3);
  std::vector<RelativePoseMeasurement> odometry = {edge(map, 0, {0.1, 0, 0}, {0, 0, 0}),
                                                   edge(map, 1, {-0.1, 0, 0}, {0, 0, 0})};
  const std::optional<Vector6d> rms = widen_by_map_disagreement(map, odometry);
  ASSERT_TRUE(rms);
  EXPECT_NEAR((*rms)[0], 0.1, 1e-12);
  for (const auto& e : odometry) {
    EXPECT_NEAR(e.information(0, 0), 1.0 / (0.02 * 0.02 + 0.01), 1e-6);
    EXPECT_NEAR(e.information(1, 1), 1.0 / (0.02 * 0.02 + 1e-12), 1e-3);
  }
}

}  // namespace
}  // namespace keel::slam
