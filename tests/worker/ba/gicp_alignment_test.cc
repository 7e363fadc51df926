// Sec. 2.5 of seed 001: GICP of DVL returns onto the CAD vertices registers the CAD to the
// world on a simulated survey (exact returns, so the truth is the answer). A doubly curved
// patch a few metres wide only weakly separates a slide along the hull from a tilt (a shifted
// paraboloid is a tilted one to second order), so what is checked is what the BA needs: the
// placed CAD surface matches the true one over the surveyed area.
#include "worker/ba/gicp_alignment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cstdio>

#include "tests/worker/ba/ba_synthetic.h"
#include "core/mesh_query.h"
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

TEST(GicpAlignment, RegistersTheCadSurfaceToTheDvlReturns) {
  testing::SyntheticHullOptions o;
  o.dvl_noise_m = 0.0;
  o.bump_height_m = 0.0;  // every return lies on the CAD surface
  const testing::SyntheticHull sim = testing::make_synthetic_hull(o);
  const auto points = true_dvl_returns(sim);
  ASSERT_GT(points.size(), 100u);
  const GicpAlignment a = align_dvl_returns_to_model(
      points, sim.problem.cad_mesh, sim.problem.T_world_model_guess, GicpOptions{});
  ASSERT_TRUE(a.ran);
  EXPECT_TRUE(a.converged);
  // True surface points over the surveyed area, and their distance to the CAD when placed
  // by the guess and by GICP.
  const MeshQuery cad(sim.problem.cad_mesh);
  const auto surface_rms = [&](const Pose3& T_world_model) {
    double sq = 0;
    int n = 0;
    for (const auto& v : sim.problem.cad_mesh.vertices) {
      if (std::abs(v.x()) > o.lane_half_length_m || std::abs(v.y()) > o.lane_spacing_m) continue;
      const double h = cad.signed_distance(T_world_model.inverse() * (sim.T_world_model * v));
      sq += h * h;
      ++n;
    }
    return std::sqrt(sq / n);
  };
  const double before = surface_rms(sim.problem.T_world_model_guess);
  const double after = surface_rms(a.T_world_model);
  std::printf("surface rms: guess %.4f m -> gicp %.4f m (fitness %.3g)\n", before, after,
              a.fitness);
  EXPECT_GT(before, 0.05);
  EXPECT_LT(after, 0.005);
}

TEST(GicpAlignment, TooFewReturnsKeepTheGuess) {
  TriangleMesh mesh = testing::make_hull_patch(testing::SyntheticHullOptions{}, false);
  Pose3 guess = Pose3::Identity();
  guess.translation() = Eigen::Vector3d(1, 2, 3);
  const GicpAlignment a = align_dvl_returns_to_model(
      {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}, mesh, guess, {});
  EXPECT_FALSE(a.ran);
  EXPECT_TRUE(a.T_world_model.isApprox(guess));
}

}  // namespace
}  // namespace keel::ba
