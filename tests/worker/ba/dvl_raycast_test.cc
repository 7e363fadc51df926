// The DVL raycast factor (Eq. 14, seed 001) against an independent brute-force cast over all
// triangles, with the beam placed through its own chain of Eigen transforms.
#include "worker/ba/dvl_raycast_factor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <limits>
#include <memory>
#include <optional>
#include <random>

#include "tests/worker/ba/ba_synthetic.h"
#include "tests/worker/ba/mesh_fixtures.h"
#include "worker/ba/pose_block.h"

namespace keel::ba {
namespace {

// Moeller-Trumbore over every face: nearest hit distance along the unit direction.
std::optional<double> brute_force_range(const TriangleMesh& mesh, const Eigen::Vector3d& o,
                                        const Eigen::Vector3d& d) {
  std::optional<double> best;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d a = mesh.vertices[f[0]];
    const Eigen::Vector3d e1 = mesh.vertices[f[1]] - a, e2 = mesh.vertices[f[2]] - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(p) / det;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    const double t = e2.dot(q) / det;
    if (u < 0 || v < 0 || u + v > 1 || t < 0) continue;
    if (!best || t < *best) best = t;
  }
  return best;
}

Pose3 random_rotation(std::mt19937& rng, double angle) {
  std::normal_distribution<double> n;
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())
                   .toRotationMatrix();
  return T;
}

void expect_factor_matches_brute_force(const TriangleMesh& mesh,
                                       const Pose3& T_model_vehicle_nominal, int trials,
                                       int* hits) {
  const MeshQuery query(mesh);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const ServoMount mount{
      make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ())),
                Eigen::Vector3d(0.4, 0.05, 0.2)),
      Eigen::Vector3d(0.1, 1.0, 0.0).normalized()};
  const Pose3 T_servo_dvl =
      make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX())),
                Eigen::Vector3d(-0.1, 0.02, 0.1));
  for (int trial = 0; trial < trials; ++trial) {
    const Pose3 T_world_model =
        random_rotation(rng, 0.5) *
        make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(u(rng), u(rng), u(rng)));
    Pose3 T_model_vehicle = T_model_vehicle_nominal * random_rotation(rng, 0.15);
    T_model_vehicle.translation() += 0.3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Pose3 T_world_vehicle = T_world_model * T_model_vehicle;
    const double theta = 0.2 * u(rng);
    const Eigen::Vector3d direction_dvl =
        Eigen::Vector3d(0.5 * u(rng), 0.5 * u(rng), 1.0).normalized();
    // Independent chain: model <- world <- vehicle <- servo(theta) <- dvl.
    Pose3 R_theta = Pose3::Identity();
    R_theta.linear() = Eigen::AngleAxisd(theta, mount.axis).toRotationMatrix();
    const Pose3 T_model_dvl = T_world_model.inverse() * T_world_vehicle *
                              mount.T_vehicle_servo_zero * R_theta * T_servo_dvl;
    const auto expected =
        brute_force_range(mesh, T_model_dvl.translation(), T_model_dvl.linear() * direction_dvl);
    const double measured = 1.7;
    const DvlBeam beam = make_dvl_beam(T_servo_dvl, direction_dvl, measured);
    const auto predicted =
        predict_dvl_range(query, mount, beam, T_world_vehicle, theta, T_world_model, 30.0);
    ASSERT_EQ(predicted.has_value(), expected.has_value()) << "trial " << trial;
    if (!expected) continue;
    ++*hits;
    EXPECT_NEAR(*predicted, *expected, 1e-9) << "trial " << trial;
    // The Ceres factor's residual is (measured - predicted) / sigma.
    std::unique_ptr<ceres::CostFunction> f(
        make_dvl_raycast_factor(query, mount, beam, 0.003, 30.0, 0.5));
    PoseBlock vehicle = to_pose_block(T_world_vehicle), model = to_pose_block(T_world_model);
    double* blocks[3] = {vehicle.data(), const_cast<double*>(&theta), model.data()};
    double r = 0;
    ASSERT_TRUE(f->Evaluate(blocks, &r, nullptr));
    EXPECT_NEAR(r, (measured - *expected) / 0.003, 1e-5);
  }
}

TEST(DvlRaycast, MatchesBruteForceOnBumpyHull) {
  testing::SyntheticHullOptions hull;
  hull.half_length_m = 1.2;
  hull.half_width_m = 1.0;
  const Pose3 below = make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, -1.5));
  int hits = 0;
  expect_factor_matches_brute_force(testing::make_hull_patch(hull, true), below, 200, &hits);
  EXPECT_GT(hits, 150);
}

TEST(DvlRaycast, MatchesBruteForceInsideSphere) {
  // From inside a closed sphere every beam hits: the far wall, through the back faces.
  int hits = 0;
  expect_factor_matches_brute_force(testing::make_icosphere(3, 4.0), Pose3::Identity(), 100, &hits);
  EXPECT_EQ(hits, 100);
}

TEST(DvlRaycast, MissGivesTheGateResidual) {
  const MeshQuery query(testing::make_box(Eigen::Vector3d(-1, -1, 5), Eigen::Vector3d(1, 1, 6)));
  const ServoMount mount;
  const DvlBeam beam = make_dvl_beam(Pose3::Identity(), Eigen::Vector3d(0, 0, -1), 2.0);  // away
  std::unique_ptr<ceres::CostFunction> f(
      make_dvl_raycast_factor(query, mount, beam, 0.003, 30.0, 0.5));
  PoseBlock vehicle = to_pose_block(Pose3::Identity()), model = to_pose_block(Pose3::Identity());
  double theta = 0;
  double* blocks[3] = {vehicle.data(), &theta, model.data()};
  double r = 0;
  ASSERT_TRUE(f->Evaluate(blocks, &r, nullptr));
  EXPECT_NEAR(r, 0.5 / 0.003, 1e-9);
}

}  // namespace
}  // namespace keel::ba
