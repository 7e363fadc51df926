// Registration on stable structure: a known rigid offset between two noisy samplings of a
// scene, one of which has changed (a new block, a removed patch), recovered within 5 mm and
// 0.05 degrees.
#include "worker/compare/stable_registration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>

#include "tests/worker/compare/test_surfaces.h"

namespace keel::compare {
namespace {

using testing::sample_box;
using testing::sample_rectangle;

// A floor, two walls at an angle and a few boxes: every degree of freedom is fixed.
std::vector<Eigen::Vector3f> scene(std::mt19937& rng, bool changed) {
  std::vector<Eigen::Vector3f> points;
  const double density = 400, sigma = 0.01;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  sample_rectangle({0, 0, 0}, X, 20, Y, 12, density, sigma, rng, &points);
  sample_rectangle({0, 12, 0}, X, 20, Z, 4, density, sigma, rng, &points);
  const Eigen::Vector3d diagonal = Eigen::Vector3d(1, -1, 0).normalized();
  sample_rectangle({20, 12, 0}, diagonal, 12, Z, 4, density, sigma, rng, &points);
  sample_box({3, 3, 0}, {4, 5, 2}, density, sigma, rng, &points);
  sample_box({12, 6, 0}, {13.5, 6.5, 1}, density, sigma, rng, &points);
  sample_box({7, 9, 0}, {7.6, 9.6, 3}, density, sigma, rng, &points);
  if (changed) sample_box({15, 2, 0}, {17, 4, 1.5}, density, sigma, rng, &points);
  return points;
}

TEST(StableRegistration, RecoversAKnownOffsetDespiteChange) {
  std::mt19937 rng(11);
  const std::vector<Eigen::Vector3f> a = scene(rng, false);
  std::vector<Eigen::Vector3f> b = scene(rng, true);
  // B's frame is off by 0.3 m and 2 degrees: p_b = T_b_a p_a.
  Pose3 T_b_a = Pose3::Identity();
  T_b_a.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d(0.2, 0.3, 1).normalized())
                       .toRotationMatrix();
  T_b_a.translation() = Eigen::Vector3d(0.2, -0.15, 0.17);
  for (auto& p : b) p = (T_b_a * p.cast<double>()).cast<float>();

  const StableRegistration r = register_stable(a, b, Pose3::Identity());
  const Pose3 error = r.T_a_b * T_b_a;  // identity when recovered
  const double angle_deg = Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI;
  EXPECT_LT(error.translation().norm(), 0.005);
  EXPECT_LT(angle_deg, 0.05);
  EXPECT_TRUE(r.converged);
  // The new block's pairs fall out of the stable band.
  EXPECT_LT(r.stable, r.correspondences);
  EXPECT_NEAR(r.rms_stable_m, 0.012, 0.008);  // two 1 cm noises, planes averaged
  EXPECT_GT(r.conditioning, 1e-6);
}

TEST(StableRegistration, IdenticalCloudsStayPut) {
  std::mt19937 rng(12);
  const std::vector<Eigen::Vector3f> a = scene(rng, false);
  // Voxel centroids near edges sit a little off the planes fitted across the edge, so the
  // identity is kept within a millimetre and a hundredth of a degree, not exactly.
  const StableRegistration r = register_stable(a, a, Pose3::Identity());
  EXPECT_LT(r.T_a_b.translation().norm(), 1e-3);
  EXPECT_LT(Eigen::AngleAxisd(r.T_a_b.linear()).angle() * 180.0 / M_PI, 0.01);
}

TEST(StableRegistration, RefusesEmptyCloudsAndBadOptions) {
  EXPECT_THROW(register_stable({}, {{0, 0, 0}}, Pose3::Identity()), std::invalid_argument);
  StableRegistrationOptions o;
  o.max_iterations = 0;
  EXPECT_THROW(validate(o), std::invalid_argument);
}

}  // namespace
}  // namespace keel::compare
