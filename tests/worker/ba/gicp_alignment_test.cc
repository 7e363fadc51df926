// Sec. 2.5 of seed 001: GICP of DVL returns onto the CAD vertices recovers the CAD-to-world
// transform of a simulated survey (exact returns: the true transform is the answer).
#include "worker/ba/gicp_alignment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cstdio>

#include "tests/worker/ba/ba_synthetic.h"
#include "worker/ba/rig_geometry.h"

namespace keel::ba {
namespace {

std::vector<Eigen::Vector3d> true_dvl_returns(const testing::SyntheticHull& sim) {
  const ServoMount mount = servo_mount(sim.problem.rig);
  std::vector<Eigen::Vector3d> points;
  for (const DvlRange& r : sim.problem.dvl_ranges) {
    const Pose3 T_world_dvl = sim.T_world_vehicle[r.keyframe] *
                              mount.T_vehicle_servo(sim.servo_angle_rad[r.keyframe]) *
                              sim.problem.rig.T_servo_dvl;
    points.push_back(T_world_dvl * (r.range_m * r.direction_dvl));
  }
  return points;
}

TEST(GicpAlignment, RecoversTheCadToWorldTransform) {
  testing::SyntheticHullOptions o;
  o.dvl_noise_m = 0.0;
  o.bump_height_m = 0.0;  // every return lies on the CAD surface
  const testing::SyntheticHull sim = testing::make_synthetic_hull(o);
  const auto points = true_dvl_returns(sim);
  ASSERT_GT(points.size(), 100u);
  const GicpAlignment a = align_dvl_returns_to_model(points, sim.problem.cad_mesh,
                                                     sim.problem.T_world_model_guess, GicpOptions{});
  ASSERT_TRUE(a.ran);
  EXPECT_TRUE(a.converged);
  const Pose3 E = sim.T_world_model.inverse() * a.T_world_model;
  const Pose3 E0 = sim.T_world_model.inverse() * sim.problem.T_world_model_guess;
  std::printf("guess error %.4f m %.3f deg -> gicp error %.4f m %.3f deg (fitness %.3g)\n",
              E0.translation().norm(), Eigen::AngleAxisd(E0.linear()).angle() * 57.2958,
              E.translation().norm(), Eigen::AngleAxisd(E.linear()).angle() * 57.2958, a.fitness);
  EXPECT_LT(Eigen::AngleAxisd(E.linear()).angle(), 0.5 * kDegToRad);
  EXPECT_LT(E.translation().norm(), 0.05);
  EXPECT_LT(E.translation().norm(), E0.translation().norm());
}

TEST(GicpAlignment, TooFewReturnsKeepTheGuess) {
  TriangleMesh mesh = testing::make_hull_patch(testing::SyntheticHullOptions{}, false);
  Pose3 guess = Pose3::Identity();
  guess.translation() = Eigen::Vector3d(1, 2, 3);
  const GicpAlignment a =
      align_dvl_returns_to_model({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}, mesh, guess, {});
  EXPECT_FALSE(a.ran);
  EXPECT_TRUE(a.T_world_model.isApprox(guess));
}

}  // namespace
}  // namespace keel::ba
