#include "worker/slam/so3.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>

namespace keel::slam {
namespace {

TEST(So3, ExpMatchesAngleAxisAndLogInvertsIt) {
  for (const Eigen::Vector3d& phi :
       {Eigen::Vector3d(0.3, -0.2, 0.9), Eigen::Vector3d(1e-9, 2e-9, -1e-9),
        Eigen::Vector3d(0, 0, M_PI - 1e-6), Eigen::Vector3d(2.0, 1.0, -0.5)}) {
    const Eigen::Matrix3d R = so3_exp(phi);
    const Eigen::Matrix3d expected =
        phi.norm() > 0 ? Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix()
                       : Eigen::Matrix3d::Identity();
    EXPECT_LT((R - expected).norm(), 1e-12);
    EXPECT_LT((so3_log(R) - phi).norm(), 1e-9) << phi.transpose();
  }
}

TEST(So3, RightJacobianMatchesFiniteDifferences) {
  const Eigen::Vector3d phi(0.4, -0.7, 0.2);
  const double h = 1e-6;
  Eigen::Matrix3d numeric;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d d = Eigen::Vector3d::Unit(k) * h;
    // Exp(phi + d) = Exp(phi) Exp(J_r d)  =>  J_r d = Log(Exp(phi)^T Exp(phi + d)).
    numeric.col(k) = so3_log(so3_exp(phi).transpose() * so3_exp(phi + d)) / h;
  }
  EXPECT_LT((numeric - right_jacobian(phi)).norm(), 1e-5);
  EXPECT_LT(
      (right_jacobian(phi) * right_jacobian_inverse(phi) - Eigen::Matrix3d::Identity()).norm(),
      1e-12);
}

TEST(So3, HatIsTheCrossProduct) {
  const Eigen::Vector3d a(1, 2, 3), b(-4, 0.5, 2);
  EXPECT_LT((hat(a) * b - a.cross(b)).norm(), 1e-15);
}

}  // namespace
}  // namespace keel::slam
