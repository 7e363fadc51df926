#include "worker/slam/so3.h"

#include <Eigen/Geometry>

#include <cmath>

namespace keel::slam {
namespace {
// Below this angle (rad) the closed forms lose precision; their Taylor series are used.
constexpr double kSmallAngle = 1e-5;
}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (theta < kSmallAngle) {
    return Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
  }
  return Eigen::Matrix3d::Identity() + (std::sin(theta) / theta) * W +
         ((1.0 - std::cos(theta)) / (theta * theta)) * W * W;
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // the short way round: angle in [0, pi]
  const Eigen::Vector3d v = q.vec();
  const double n = v.norm();
  if (n < kSmallAngle) {
    // theta = 2 atan(n / w) ~= 2 n / w (1 - n^2 / (3 w^2)).
    return (2.0 / q.w()) * (1.0 - n * n / (3.0 * q.w() * q.w())) * v;
  }
  return (2.0 * std::atan2(n, q.w()) / n) * v;
}

Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (theta < kSmallAngle) {
    return Eigen::Matrix3d::Identity() - 0.5 * W + (1.0 / 6.0) * W * W;
  }
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() - ((1.0 - std::cos(theta)) / t2) * W +
         ((theta - std::sin(theta)) / (t2 * theta)) * W * W;
}

Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (theta < kSmallAngle) {
    return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / 12.0) * W * W;
  }
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + 0.5 * W +
         (1.0 / t2 - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta))) * W * W;
}

}  // namespace keel::slam
