// The MAP noise estimate against series with known noise: white scatter plus a random walk
// along a known direction over the degenerate stretch, recovered from the differences alone.
#include "worker/slam/map_pose_noise.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

struct Series {
  std::vector<Pose3> truth, map;
  std::vector<double> drift_path;
};

// A straight run along x at `step_m` per keyframe; the MAP has white noise (sigma_t per axis,
// sigma_r per body axis) and, over keyframes [degenerate_begin, degenerate_end), a random walk
// along `axis` of drift_per_sqrt_m per sqrt(m).
Series make_series(int n, double step_m, double sigma_t, double sigma_r, double drift_per_sqrt_m,
                   const Eigen::Vector3d& axis, int degenerate_begin, int degenerate_end,
                   unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  auto gaussian3 = [&] { return Eigen::Vector3d(g(rng), g(rng), g(rng)); };
  Series s;
  double walk = 0.0, path = 0.0;
  for (int k = 0; k < n; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(step_m * k, 0.0, 0.0);
    T.linear() = so3_exp(Eigen::Vector3d(0.0, 0.0, 0.01 * k));
    const bool degenerate = k >= degenerate_begin && k < degenerate_end && k > 0;
    if (degenerate) {
      walk += drift_per_sqrt_m * std::sqrt(step_m) * g(rng);
      path += step_m;
    }
    Pose3 M = T;
    M.translation() += sigma_t * gaussian3() + walk * axis.normalized();
    M.linear() = T.linear() * so3_exp(sigma_r * gaussian3());
    s.truth.push_back(T);
    s.map.push_back(M);
    s.drift_path.push_back(path);
  }
  return s;
}

double sigma_along(const Eigen::Matrix3d& covariance, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d u = direction.normalized();
  return std::sqrt(u.dot(covariance * u));
}

TEST(MapPoseNoise, RecoversWhiteNoiseAndDriftAlongTheDegenerateAxis) {
  const Eigen::Vector3d axis(1.0, 1.0, 0.0);
  const Series s = make_series(4000, 1.0, 0.03, 0.005, 0.06, axis, 0, 4000, 7);
  const MapPoseNoise n = estimate_map_pose_noise(s.map, s.truth, s.drift_path);
  // 4000 keyframes: the moments are good to a few percent.
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(std::sqrt(n.translation_covariance(a, a)), 0.03, 0.004) << a;
    EXPECT_NEAR(std::sqrt(n.rotation_covariance(a, a)), 0.005, 0.0003) << a;
  }
  EXPECT_NEAR(sigma_along(n.drift_covariance_per_m, axis), 0.06, 0.006);
  // Across the axis there is no drift: at most a sampling residue, far below the walk.
  EXPECT_LT(sigma_along(n.drift_covariance_per_m, Eigen::Vector3d(1.0, -1.0, 0.0)), 0.015);
  EXPECT_LT(sigma_along(n.drift_covariance_per_m, Eigen::Vector3d::UnitZ()), 0.015);
}

TEST(MapPoseNoise, WithoutDegeneracyTheDriftStaysAtItsFloor) {
  const Series s = make_series(1000, 1.0, 0.03, 0.005, 0.06, Eigen::Vector3d::UnitX(), 0, 0, 8);
  for (double d : s.drift_path) ASSERT_EQ(d, 0.0);
  MapNoiseEstimateOptions o;
  const MapPoseNoise n = estimate_map_pose_noise(s.map, s.truth, s.drift_path, o);
  const double floor = o.min_drift_per_sqrt_m * o.min_drift_per_sqrt_m;
  EXPECT_TRUE(n.drift_covariance_per_m.isApprox(floor * Eigen::Matrix3d::Identity(), 1e-9));
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(std::sqrt(n.translation_covariance(a, a)), 0.03, 0.003) << a;
}

// Only differences enter, so a reference that is off the truth by a constant offset and a
// constant rotation gives the same estimate as the truth itself.
TEST(MapPoseNoise, IgnoresAConstantOffsetOfTheReference) {
  const Series s = make_series(500, 1.2, 0.03, 0.005, 0.05, Eigen::Vector3d::UnitX(), 100, 400, 9);
  std::vector<Pose3> shifted = s.truth;
  for (Pose3& T : shifted) T.translation() += Eigen::Vector3d(0.4, -0.2, 0.1);
  const MapPoseNoise a = estimate_map_pose_noise(s.map, s.truth, s.drift_path);
  const MapPoseNoise b = estimate_map_pose_noise(s.map, shifted, s.drift_path);
  EXPECT_TRUE(a.translation_covariance.isApprox(b.translation_covariance, 1e-9));
  EXPECT_TRUE(a.drift_covariance_per_m.isApprox(b.drift_covariance_per_m, 1e-9));
}

TEST(MapPoseNoise, PositionCovarianceGrowsWithTheDriftPath) {
  const MapPoseNoise n = MapPoseNoise::isotropic(0.03, 0.01, 0.06);
  EXPECT_NEAR(n.position_covariance(0.0)(0, 0), 0.03 * 0.03, 1e-15);
  EXPECT_NEAR(n.position_covariance(25.0)(1, 1), 0.03 * 0.03 + 0.06 * 0.06 * 25.0, 1e-15);
  EXPECT_EQ(n.position_covariance(25.0)(0, 1), 0.0);
}

TEST(MapPoseNoise, PathLengthsAddTheSteps) {
  std::vector<Pose3> poses(3, Pose3::Identity());
  poses[1].translation() = Eigen::Vector3d(3.0, 4.0, 0.0);
  poses[2].translation() = Eigen::Vector3d(3.0, 4.0, 2.0);
  const std::vector<double> s = path_lengths(poses);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_DOUBLE_EQ(s[1], 5.0);
  EXPECT_DOUBLE_EQ(s[2], 7.0);
}

TEST(MapPoseNoise, RejectsMismatchedOrTooFewPoses) {
  const Series s = make_series(10, 1.0, 0.03, 0.005, 0.0, Eigen::Vector3d::UnitX(), 0, 0, 1);
  std::vector<Pose3> short_reference(s.truth.begin(), s.truth.begin() + 9);
  EXPECT_THROW(estimate_map_pose_noise(s.map, short_reference, s.drift_path),
               std::invalid_argument);
  std::vector<Pose3> two(s.map.begin(), s.map.begin() + 2);
  EXPECT_THROW(estimate_map_pose_noise(two, two, {0.0, 0.0}), std::invalid_argument);
}

}  // namespace
}  // namespace keel::slam
