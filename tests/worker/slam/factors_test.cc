// Analytic Jacobians of every residual against central differences taken on the manifold
// (poses, velocities, both biases, s_d, the DVL-IMU extrinsic rotation).
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Core>

#include <memory>
#include <random>
#include <vector>

#include "worker/slam/dvl_factor.h"
#include "worker/slam/imu_factor.h"
#include "worker/slam/information.h"
#include "worker/slam/manifolds.h"
#include "worker/slam/prior_factors.h"
#include "worker/slam/relative_pose_factor.h"
#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

using Block = std::vector<double>;

Eigen::VectorXd evaluate(const ceres::CostFunction& f, const std::vector<Block>& blocks) {
  std::vector<const double*> ptrs;
  for (const Block& b : blocks) ptrs.push_back(b.data());
  Eigen::VectorXd r(f.num_residuals());
  EXPECT_TRUE(f.Evaluate(ptrs.data(), r.data(), nullptr));
  return r;
}

// Compares J_ambient * PlusJacobian with (r(x [+] h e_k) - r(x [+] -h e_k)) / 2h per block.
void expect_jacobians_match(const ceres::CostFunction& f, const std::vector<Block>& blocks,
                            const std::vector<const ceres::Manifold*>& manifolds,
                            double rel_tol = 1e-6) {
  const int m = f.num_residuals();
  std::vector<const double*> ptrs;
  std::vector<std::vector<double>> jac(blocks.size());
  std::vector<double*> jac_ptrs;
  for (size_t b = 0; b < blocks.size(); ++b) {
    ptrs.push_back(blocks[b].data());
    jac[b].resize(m * blocks[b].size());
    jac_ptrs.push_back(jac[b].data());
  }
  Eigen::VectorXd r(m);
  ASSERT_TRUE(f.Evaluate(ptrs.data(), r.data(), jac_ptrs.data()));
  ASSERT_GT(r.norm(), 0.0) << "test at a non-zero residual";
  for (size_t b = 0; b < blocks.size(); ++b) {
    const int ambient = static_cast<int>(blocks[b].size());
    const ceres::Manifold* man = manifolds[b];
    const int tangent = man ? man->TangentSize() : ambient;
    Eigen::MatrixXd P = Eigen::MatrixXd::Identity(ambient, tangent);
    if (man) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Pr(ambient, tangent);
      man->PlusJacobian(blocks[b].data(), Pr.data());
      P = Pr;
    }
    const Eigen::MatrixXd J_amb =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            jac[b].data(), m, ambient);
    const Eigen::MatrixXd J = J_amb * P;
    Eigen::MatrixXd numeric(m, tangent);
    const double h = 1e-6;
    for (int k = 0; k < tangent; ++k) {
      std::vector<Block> plus = blocks, minus = blocks;
      Eigen::VectorXd d = Eigen::VectorXd::Zero(tangent);
      d(k) = h;
      if (man) {
        man->Plus(blocks[b].data(), d.data(), plus[b].data());
        d(k) = -h;
        man->Plus(blocks[b].data(), d.data(), minus[b].data());
      } else {
        plus[b][k] += h;
        minus[b][k] -= h;
      }
      numeric.col(k) = (evaluate(f, plus) - evaluate(f, minus)) / (2 * h);
    }
    const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
    EXPECT_LT((J - numeric).cwiseAbs().maxCoeff(), rel_tol * scale)
        << "parameter block " << b << "\nanalytic\n"
        << J << "\nnumeric\n"
        << numeric;
  }
}

Block pose_block(const Eigen::Vector3d& phi, const Eigen::Vector3d& p) {
  Block b(7);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3_exp(phi);
  T.translation() = p;
  set_pose_block(T, b.data());
  return b;
}

Block rotation_block(const Eigen::Vector3d& phi) {
  Block b(4);
  set_rotation_block(so3_exp(phi), b.data());
  return b;
}

Block vec(double x, double y, double z) { return {x, y, z}; }

Eigen::MatrixXd random_sqrt_info(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = u(rng);
  return sqrt_information(A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n));
}

const PoseManifold kPose;
const RotationManifold kRotation;

TEST(FactorJacobians, RelativePose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3_exp(Eigen::Vector3d(0.1, -0.3, 0.7));
  T.translation() = Eigen::Vector3d(1.0, 0.4, -0.2);
  RelativePoseFactor f(T, random_sqrt_info(6, 1));
  expect_jacobians_match(
      f, {pose_block({0.2, 0.1, -0.4}, {1, 2, 3}), pose_block({0.5, -0.2, 0.1}, {2.1, 2.2, 2.7})},
      {&kPose, &kPose});
}

TEST(FactorJacobians, PosePriorAndRotationPrior) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3_exp(Eigen::Vector3d(0.3, 0.2, -0.1));
  PosePriorFactor pose(T, random_sqrt_info(6, 2));
  expect_jacobians_match(pose, {pose_block({0.1, 0.4, 0.2}, {0.5, -1, 2})}, {&kPose});
  RotationPriorFactor rot(so3_exp(Eigen::Vector3d(0.0, 0.1, 0.2)), random_sqrt_info(3, 3));
  expect_jacobians_match(rot, {rotation_block({0.3, -0.2, 0.25})}, {&kRotation});
}

TEST(FactorJacobians, MapAnchorAndVectorRandomWalk) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3_exp(Eigen::Vector3d(-0.2, 0.1, 0.6));
  T.translation() = Eigen::Vector3d(3.0, -1.0, 0.4);
  MapAnchorFactor anchor(T, random_sqrt_info(6, 4));
  expect_jacobians_match(anchor,
                         {pose_block({-0.1, 0.2, 0.5}, {3.2, -0.8, 0.3}), vec(0.1, -0.2, 0.05)},
                         {&kPose, nullptr});
  VectorRandomWalkFactor walk(random_sqrt_info(3, 5));
  expect_jacobians_match(walk, {vec(0.1, 0.2, 0.3), vec(0.2, 0.1, -0.3)}, {nullptr, nullptr});
}

// The anchor's residual is the translation minus the drift: a pose at MAP + drift fits exactly.
TEST(MapAnchorFactor, ResidualIsPositionMinusMapMinusDrift) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3_exp(Eigen::Vector3d(0.0, 0.0, 0.3));
  T.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  MapAnchorFactor anchor(T, Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::VectorXd r =
      evaluate(anchor, {pose_block({0.0, 0.0, 0.3}, {1.5, 2.0, 3.0}), vec(0.5, 0.0, 0.0)});
  EXPECT_LT(r.norm(), 1e-12);
  const Eigen::VectorXd r2 =
      evaluate(anchor, {pose_block({0.0, 0.0, 0.3}, {1.5, 2.0, 3.0}), vec(0.0, 0.1, 0.0)});
  EXPECT_NEAR(r2(0), 0.5, 1e-12);
  EXPECT_NEAR(r2(1), -0.1, 1e-12);
}

TEST(FactorJacobians, BiasRandomWalk) {
  BiasRandomWalkFactor f(1e-4, 0.7);
  expect_jacobians_match(f, {vec(0.1, 0.2, 0.3), vec(0.2, 0.1, -0.3)}, {nullptr, nullptr});
}

std::shared_ptr<ImuPreintegration> imu_preintegration() {
  auto pre = std::make_shared<ImuPreintegration>(Eigen::Vector3d(0.01, -0.02, 0.01),
                                                 Eigen::Vector3d(0.1, 0.0, -0.1), ImuNoise{});
  for (int k = 0; k < 200; ++k) {
    const double t = k * 0.005;
    pre->integrate(Eigen::Vector3d(0.2 * std::sin(t), 0.1, 0.4 * std::cos(2 * t)),
                   Eigen::Vector3d(0.5, 0.2 * t, 9.8), 0.005);
  }
  return pre;
}

TEST(FactorJacobians, ImuWithAndWithoutPositionResidual) {
  const auto pre = imu_preintegration();
  const std::vector<Block> blocks = {
      pose_block({0.1, -0.05, 0.3}, {1, 2, 0.5}),
      vec(1.0, 0.3, -0.1),
      vec(0.015, -0.025, 0.012),  // b^w away from the linearisation point
      vec(0.12, -0.03, -0.09),    // b^a likewise
      pose_block({0.15, 0.02, 0.7}, {2.1, 2.5, 0.4}),
      vec(1.1, 0.5, 0.0)};
  const std::vector<const ceres::Manifold*> man = {&kPose,  nullptr, nullptr,
                                                   nullptr, &kPose,  nullptr};
  for (bool with_position : {true, false}) {
    ImuFactor f(pre, Eigen::Vector3d(0, 0, -9.81), imu_sqrt_information(*pre, with_position));
    expect_jacobians_match(f, blocks, man, 1e-5);
  }
}

TEST(FactorJacobians, Dvl) {
  auto pre = std::make_shared<DvlPreintegration>(
      Eigen::Vector3d(0.01, 0.0, -0.01), Eigen::Vector3d(0.02, -0.01, 0.0), 1.01,
      so3_exp(Eigen::Vector3d(0.0, 0.02, 0.1)), DvlNoise{}, 5.7e-4);
  for (int k = 0; k < 200; ++k) {
    const double t = k * 0.005;
    pre->integrate(Eigen::Vector3d(0.1 * std::sin(t), 0.05, 0.3),
                   Eigen::Vector3d(1.2, 0.1 * std::cos(t), 0.02), 0.005, 0.05);
  }
  DvlFactor f(pre, Eigen::Vector3d(0.3, -0.1, -0.5),
              sqrt_information_from_covariance(pre->position_covariance()));
  const std::vector<Block> blocks = {pose_block({0.1, -0.05, 0.3}, {1, 2, 0.5}),
                                     vec(0.012, 0.003, -0.008),
                                     vec(0.025, -0.012, 0.004),
                                     pose_block({0.12, -0.02, 0.62}, {2.1, 2.4, 0.5}),
                                     Block{1.03},
                                     rotation_block({0.01, 0.03, 0.12})};
  const std::vector<const ceres::Manifold*> man = {&kPose, nullptr, nullptr,
                                                   &kPose, nullptr, &kRotation};
  // Whitened by a ~1e4 sqrt-information, so compare relative to the entries' scale.
  expect_jacobians_match(f, blocks, man, 1e-5);
}

}  // namespace
}  // namespace keel::slam
