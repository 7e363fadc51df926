#include "worker/ba/rigid_ransac.h"

#include <Eigen/Geometry>

#include <random>
#include <stdexcept>

namespace keel::ba {
namespace {

Pose3 fit_rigid(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                const std::vector<int>& indices) {
  Eigen::Matrix3Xd src(3, indices.size()), dst(3, indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    src.col(i) = b[indices[i]];
    dst.col(i) = a[indices[i]];
  }
  Pose3 T = Pose3::Identity();
  T.matrix() = Eigen::umeyama(src, dst, /*with_scaling=*/false);
  return T;
}

std::vector<int> inliers_of(const std::vector<Eigen::Vector3d>& a,
                            const std::vector<Eigen::Vector3d>& b, const Pose3& T,
                            double threshold) {
  std::vector<int> inliers;
  for (size_t i = 0; i < a.size(); ++i) {
    if ((a[i] - T * b[i]).norm() <= threshold) inliers.push_back(static_cast<int>(i));
  }
  return inliers;
}

}  // namespace

std::optional<RigidRansacResult> rigid_ransac(const std::vector<Eigen::Vector3d>& points_a,
                                              const std::vector<Eigen::Vector3d>& points_b,
                                              double inlier_threshold_m, int iterations,
                                              uint32_t seed) {
  if (points_a.size() != points_b.size()) {
    throw std::invalid_argument("rigid_ransac: point sets differ in size");
  }
  const int n = static_cast<int>(points_a.size());
  if (n < 3) return std::nullopt;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> best;
  for (int it = 0; it < iterations; ++it) {
    const int i = pick(rng), j = pick(rng), k = pick(rng);
    if (i == j || j == k || i == k) continue;
    // A degenerate (collinear) sample leaves the rotation about the line free.
    const Eigen::Vector3d cross = (points_b[j] - points_b[i]).cross(points_b[k] - points_b[i]);
    if (cross.norm() < 1e-9) continue;
    std::vector<int> inliers = inliers_of(
        points_a, points_b, fit_rigid(points_a, points_b, {i, j, k}), inlier_threshold_m);
    if (inliers.size() > best.size()) best = std::move(inliers);
  }
  if (best.size() < 3) return std::nullopt;
  RigidRansacResult result;
  result.T_a_b = fit_rigid(points_a, points_b, best);
  const std::vector<int> final_inliers =
      inliers_of(points_a, points_b, result.T_a_b, inlier_threshold_m);
  result.inliers.assign(n, false);
  for (int i : final_inliers) result.inliers[i] = true;
  result.num_inliers = static_cast<int>(final_inliers.size());
  return result;
}

}  // namespace keel::ba
