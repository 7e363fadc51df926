// GICP odometry between synthetic scans: recovers a known motion in a room, and its
// information reveals the degenerate axis of a corridor.
#include "worker/slam/gicp_odometry.h"

#include <gtest/gtest.h>

#include <random>

#include "worker/slam/degeneracy.h"
#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

// Points on the walls of an axis-aligned box (a room) or on two walls and a floor infinite
// along x (a corridor), seen from the body at T_world_body, returned in the body frame.
PointCloud scan(const Pose3& T_world_body, bool corridor, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0, 0.005);
  std::vector<Eigen::Vector3d> world;
  for (int k = 0; k < 6000; ++k) {
    const double a = u(rng), b = u(rng);
    const int face = k % (corridor ? 3 : 6);
    Eigen::Vector3d p;
    if (corridor) {  // walls y = +-3, floor z = -1.5, along x in [-15, 15]
      if (face == 0)
        p = {15 * a, 3, 1.5 * b};
      else if (face == 1)
        p = {15 * a, -3, 1.5 * b};
      else
        p = {15 * a, 3 * b, -1.5};
    } else {  // room [-8, 8] x [-5, 5] x [-2, 2] with a pillar for good measure
      switch (face) {
        case 0:
          p = {8, 5 * a, 2 * b};
          break;
        case 1:
          p = {-8, 5 * a, 2 * b};
          break;
        case 2:
          p = {8 * a, 5, 2 * b};
          break;
        case 3:
          p = {8 * a, -5, 2 * b};
          break;
        case 4:
          p = {8 * a, 5 * b, -2};
          break;
        default:
          p = {2 + 0.5 * a, 1 + 0.5 * b, 2 * u(rng)};
          break;
      }
    }
    world.push_back(p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  PointCloud c;
  for (const auto& p : world) c.xyz.push_back((T_world_body.inverse() * p).cast<float>());
  return c;
}

Pose3 pose(double x, double y, double yaw) {
  return make_pose(Eigen::Quaterniond(so3_exp(Eigen::Vector3d(0, 0, yaw))),
                   Eigen::Vector3d(x, y, 0));
}

TEST(GicpOdometry, RecoversAKnownMotionInARoom) {
  const std::vector<Pose3> truth = {pose(0, 0, 0), pose(0.8, 0.3, 0.1), pose(1.5, 0.2, 0.15)};
  std::vector<PointCloud> scans;
  for (size_t k = 0; k < truth.size(); ++k) {
    scans.push_back(scan(truth[k], false, 10 + k));
    scans.back().t_ns = static_cast<TimeNs>(k) * 1'000'000'000;
  }
  // Initial guesses off by 0.2 m and 3 degrees.
  std::vector<Pose3> guess = {pose(0, 0, 0), pose(0.6, 0.4, 0.05), pose(1.3, 0.1, 0.2)};
  GicpOdometryOptions o;
  o.voxel_leaf_m = 0.1;
  const auto edges = relative_poses_from_scans(scans, Pose3::Identity(), guess, o);
  ASSERT_EQ(edges.size(), 2u);
  for (size_t k = 0; k < edges.size(); ++k) {
    const Pose3 expected = truth[k].inverse() * truth[k + 1];
    EXPECT_LT((edges[k].T_i_j.translation() - expected.translation()).norm(), 0.02) << k;
    EXPECT_LT(so3_log(expected.linear().transpose() * edges[k].T_i_j.linear()).norm(), 0.005);
    EXPECT_FALSE(analyze_degeneracy(edges[k].information).degenerate) << k;
    EXPECT_EQ(edges[k].t_j_ns, scans[k + 1].t_ns);
  }
}

TEST(GicpOdometry, CorridorInformationIsDegenerateAlongTheCorridor) {
  const PointCloud a = scan(pose(0, 0, 0), true, 1), b = scan(pose(0.5, 0, 0), true, 2);
  const Matrix6d H = point_to_plane_information(a, b, pose(0.5, 0, 0));
  const DegeneracyReport r = analyze_degeneracy(H);
  EXPECT_TRUE(r.degenerate);
  // The weak direction is x (the corridor axis): the kept information has nothing along x and
  // keeps y and z.
  EXPECT_LT(H(0, 0), 1e-2 * H(1, 1));
  const Eigen::Matrix3d kept = r.well_conditioned_information.topLeftCorner<3, 3>();
  EXPECT_LT(kept(0, 0), 1e-3 * H(1, 1));
  EXPECT_GT(r.well_conditioned_information(1, 1), 0.5 * H(1, 1));
  EXPECT_GT(r.eigenvalues_translation(1), 1e3);
}

TEST(GicpOdometry, RejectsMismatchedInputs) {
  std::vector<PointCloud> scans(2);
  EXPECT_THROW(relative_poses_from_scans(scans, Pose3::Identity(), {Pose3::Identity()}),
               std::invalid_argument);
}

}  // namespace
}  // namespace keel::slam
