// The surface constraint, Eq. (4)-(7) of seed 001: the max-mixture picks the component of
// larger likelihood, its cost is -log of the normalised max-mixture (continuous at the
// switch), and h is the signed distance (closed forms on a box).
#include "worker/ba/surface_factor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>

#include "tests/core/mesh_fixtures.h"
#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// -log of the normalised Gaussian density N(e; 0, sigma^2).
double neg_log_gaussian(double e, double sigma) {
  return 0.5 * e * e / (sigma * sigma) + std::log(sigma) + 0.5 * std::log(2 * M_PI);
}

TEST(MaxMixture, PicksTheMoreLikelyComponent) {
  const MaxMixture mixture{1.0, 0.02};
  for (double e : {0.0, 0.01, -0.03, 0.05, -0.055}) EXPECT_EQ(mixture.label(e), 1) << e;
  for (double e : {0.057, -0.06, 0.1, -0.3, 2.0}) EXPECT_EQ(mixture.label(e), 0) << e;
  // Brute force over both normalised densities.
  for (double e = -0.5; e <= 0.5; e += 0.001) {
    const int expected = neg_log_gaussian(e, 0.02) <= neg_log_gaussian(e, 1.0) ? 1 : 0;
    EXPECT_EQ(mixture.label(e), expected) << e;
  }
}

TEST(MaxMixture, SwitchingDistanceClosedForm) {
  const MaxMixture mixture{1.0, 0.02};
  // e^2 / s1^2 + 2 log s1 = e^2 / s0^2 + 2 log s0  =>  e^2 = 2 log(50) / (2500 - 1).
  const double expected = std::sqrt(2.0 * std::log(50.0) / (2500.0 - 1.0));
  EXPECT_NEAR(mixture.switching_distance_m(), expected, 1e-12);
  EXPECT_NEAR(expected, 0.05596, 1e-5);  // the "about 5 cm" of Fig. 7
}

TEST(MaxMixture, CostIsNegLogOfNormalisedMaxMixtureUpToAConstant) {
  const MaxMixture mixture{1.0, 0.02};
  // -log(eta max_l N(e; 0, s_l^2)) - (-log N(0; 0, s_1^2)) equals our cost for every e.
  const double constant = neg_log_gaussian(0.0, 0.02);
  for (double e = -1.0; e <= 1.0; e += 0.0037) {
    const double reference =
        std::min(neg_log_gaussian(e, 0.02), neg_log_gaussian(e, 1.0)) - constant;
    EXPECT_NEAR(mixture.cost(e), reference, 1e-9) << e;
  }
}

TEST(MaxMixture, CostIsContinuousAcrossTheSwitch) {
  const MaxMixture mixture{1.0, 0.02};
  const double s = mixture.switching_distance_m();
  for (double sign : {1.0, -1.0}) {
    for (double eps : {1e-4, 1e-6, 1e-8}) {
      const double inside = sign * (s - eps), outside = sign * (s + eps);
      ASSERT_EQ(mixture.label(inside), 1);
      ASSERT_EQ(mixture.label(outside), 0);
      // Lipschitz bound: the steeper component has slope s / sigma_1^2 at the switch.
      const double slope = s / (0.02 * 0.02);
      EXPECT_LE(std::abs(mixture.cost(outside) - mixture.cost(inside)), 2.0 * eps * slope * 1.01)
          << "eps " << eps;
    }
  }
  // The jump a cost without the normalisation residual would have at the switch.
  const double unnormalised_jump = 0.5 * s * s * (1.0 / (0.02 * 0.02) - 1.0);
  EXPECT_GT(unnormalised_jump, 3.0);
}

// The Ceres factor on a box [0,1]^3 placed by x_gM: h against closed-form signed distances
// (face, edge and vertex regions, inside and outside), residuals per component and mode.
class SurfaceFactorOnBox : public ::testing::Test {
 protected:
  SurfaceFactorOnBox()
      : mesh_(testing::make_box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones())) {
    T_world_model_ = make_pose(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized())),
        Eigen::Vector3d(2.0, -1.0, 0.5));
  }
  // Residuals of the factor for a landmark given in the model frame.
  Eigen::Vector2d residuals(const Eigen::Vector3d& l_model, SurfaceMode mode) {
    std::unique_ptr<ceres::CostFunction> f(make_surface_factor(mesh_, mixture_, mode, 0.0));
    PoseBlock model = to_pose_block(T_world_model_);
    Eigen::Vector3d l_world = T_world_model_ * l_model;
    double* blocks[2] = {model.data(), l_world.data()};
    Eigen::Vector2d r;
    EXPECT_TRUE(f->Evaluate(blocks, r.data(), nullptr));
    return r;
  }
  MeshQuery mesh_;
  Pose3 T_world_model_;
  MaxMixture mixture_{1.0, 0.02};
};

TEST_F(SurfaceFactorOnBox, SignedDistanceMatchesClosedForm) {
  struct Case {
    Eigen::Vector3d p;
    double h;
  };
  const Case cases[] = {
      {{0.5, 0.5, 1.3}, 0.3},                // above the top face
      {{0.5, 0.5, 0.9}, -0.1},               // inside, nearest the top face
      {{0.3, -0.02, 0.4}, 0.02},             // just outside a side face
      {{1.2, 0.5, 1.2}, std::sqrt(0.08)},    // edge region
      {{-0.1, -0.2, 1.2}, std::sqrt(0.09)},  // vertex region
      {{0.5, 0.45, 0.5}, -0.45},             // deep inside
  };
  for (const Case& c : cases) {
    EXPECT_NEAR(signed_distance_to_model(mesh_, T_world_model_, T_world_model_ * c.p), c.h, 1e-9)
        << c.p.transpose();
    // Residual 0 is (z_s - h) / sigma_lambda with z_s = 0.
    const Eigen::Vector2d r = residuals(c.p, SurfaceMode::kOnModel);
    EXPECT_NEAR(r[0], -c.h / 0.02, 1e-6);
    EXPECT_EQ(r[1], 0.0);
  }
}

TEST_F(SurfaceFactorOnBox, MaxMixtureResidualsPerComponent) {
  // 2 cm outside the top face: lambda = 1, r = [-h / sigma_1, 0].
  Eigen::Vector2d r = residuals({0.5, 0.5, 1.02}, SurfaceMode::kMaxMixture);
  EXPECT_NEAR(r[0], -1.0, 1e-9);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  // 30 cm outside: lambda = 0, r = [-h / sigma_0, sqrt(2 log(sigma_0 / sigma_1))].
  r = residuals({0.5, 0.5, 1.3}, SurfaceMode::kMaxMixture);
  EXPECT_NEAR(r[0], -0.3, 1e-9);
  EXPECT_NEAR(r[1], std::sqrt(2.0 * std::log(50.0)), 1e-12);
  EXPECT_NEAR(0.5 * r.squaredNorm(), mixture_.cost(-0.3), 1e-12);
  // geva keeps lambda = 1 however far.
  r = residuals({0.5, 0.5, 1.3}, SurfaceMode::kOnModel);
  EXPECT_NEAR(r[0], -0.3 / 0.02, 1e-9);
}

TEST_F(SurfaceFactorOnBox, FactorCostContinuousAtTheSwitch) {
  const double s = mixture_.switching_distance_m();
  const double eps = 1e-7;
  const Eigen::Vector2d below = residuals({0.5, 0.5, 1.0 + s - eps}, SurfaceMode::kMaxMixture);
  const Eigen::Vector2d above = residuals({0.5, 0.5, 1.0 + s + eps}, SurfaceMode::kMaxMixture);
  EXPECT_EQ(below[1], 0.0);  // lambda = 1 side
  EXPECT_GT(above[1], 0.0);  // lambda = 0 side
  EXPECT_NEAR(0.5 * below.squaredNorm(), 0.5 * above.squaredNorm(), 1e-3);
}

// The closed-form Jacobian against central differences in the ambient parameters (all 7 of
// x_gM, the quaternion not normalised: the factor normalises it) in the face, edge and vertex
// regions of the box, inside and outside, for both components and both modes.
TEST_F(SurfaceFactorOnBox, ClosedFormJacobianMatchesCentralDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.6, 1.6);
  std::uniform_real_distribution<double> scale(0.5, 2.0);
  int checked = 0;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d l_model(u(rng), u(rng), u(rng));
    const ClosestPoint closest = mesh_.closest_point(l_model);
    // The distance is not differentiable on the medial axis (inside the box, equidistant to
    // two faces) nor on the surface: skip points within 1 mm of either.
    if (closest.distance_m < 1e-3) continue;
    const Eigen::Vector3d c = l_model.cwiseMin(Eigen::Vector3d::Ones() - l_model);
    if (closest.signed_distance_m < 0) {
      std::array<double, 3> d{c.x(), c.y(), c.z()};
      std::sort(d.begin(), d.end());
      if (d[1] - d[0] < 1e-3) continue;
    }
    for (SurfaceMode mode : {SurfaceMode::kMaxMixture, SurfaceMode::kOnModel}) {
      std::unique_ptr<ceres::CostFunction> f(make_surface_factor(mesh_, mixture_, mode, 0.01));
      PoseBlock model = to_pose_block(T_world_model_);
      const double s = scale(rng);
      for (int k = 0; k < 4; ++k) model[k] *= s;
      Eigen::Vector3d l_world = T_world_model_ * l_model;
      double* blocks[2] = {model.data(), l_world.data()};
      Eigen::Matrix<double, 2, 7, Eigen::RowMajor> J_model;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_landmark;
      double* jacobians[2] = {J_model.data(), J_landmark.data()};
      Eigen::Vector2d r;
      ASSERT_TRUE(f->Evaluate(blocks, r.data(), jacobians));
      EXPECT_NEAR(r[0],
                  (0.01 - closest.signed_distance_m) /
                      mixture_.sigma(mode == SurfaceMode::kOnModel
                                         ? 1
                                         : mixture_.label(0.01 - closest.signed_distance_m)),
                  1e-9);
      const double h = 1e-7;
      for (int b = 0; b < 2; ++b) {
        const int n = b == 0 ? 7 : 3;
        for (int k = 0; k < n; ++k) {
          const double x0 = blocks[b][k];
          Eigen::Vector2d plus, minus;
          blocks[b][k] = x0 + h;
          ASSERT_TRUE(f->Evaluate(blocks, plus.data(), nullptr));
          blocks[b][k] = x0 - h;
          ASSERT_TRUE(f->Evaluate(blocks, minus.data(), nullptr));
          blocks[b][k] = x0;
          const Eigen::Vector2d numeric = (plus - minus) / (2 * h);
          const double analytic = b == 0 ? J_model(0, k) : J_landmark(0, k);
          // Relative to the residual's scale (1 / sigma per metre).
          ASSERT_NEAR(analytic, numeric[0], 1e-5 * (1.0 + std::abs(numeric[0])))
              << "block " << b << " k " << k << " at " << l_model.transpose();
          ASSERT_EQ(b == 0 ? J_model(1, k) : J_landmark(1, k), 0.0);
          ASSERT_NEAR(numeric[1], 0.0, 1e-9);  // unless a step crossed the switch
        }
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

// A factor keeps its landmark's nearby faces between evaluations: walking a landmark through
// the face, edge and vertex regions and inside, its residuals stay those of a fresh tree query.
TEST_F(SurfaceFactorOnBox, CachedFactorFollowsAMovingLandmark) {
  std::unique_ptr<ceres::CostFunction> f(
      make_surface_factor(mesh_, mixture_, SurfaceMode::kOnModel, 0.0));
  PoseBlock model = to_pose_block(T_world_model_);
  std::mt19937 rng(9);
  std::normal_distribution<double> step(0.0, 0.01);
  Eigen::Vector3d l_model(0.5, 0.5, 1.2);
  const Eigen::Vector3d goal(1.3, -0.2, -0.1);  // through the top face, an edge, a corner
  for (int k = 0; k < 400; ++k) {
    l_model += 0.005 * (goal - Eigen::Vector3d(0.5, 0.5, 1.2)) +
               Eigen::Vector3d(step(rng), step(rng), step(rng));
    if (k == 200) l_model = Eigen::Vector3d(0.4, 0.45, 0.5);  // a jump inside
    Eigen::Vector3d l_world = T_world_model_ * l_model;
    double* blocks[2] = {model.data(), l_world.data()};
    Eigen::Vector2d r;
    ASSERT_TRUE(f->Evaluate(blocks, r.data(), nullptr));
    const double h = signed_distance_to_model(mesh_, T_world_model_, l_world);
    ASSERT_NEAR(r[0], -h / 0.02, 1e-7) << k << " " << l_model.transpose();
  }
}

}  // namespace
}  // namespace keel::ba
