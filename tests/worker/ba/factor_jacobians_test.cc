// Every BA factor's auto-diff Jacobian against central numerical differences on the
// parameter manifolds (our own central differences), at random states.
#include <ceres/cost_function.h>
#include <ceres/product_manifold.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <memory>
#include <random>

#include "tests/worker/ba/ba_synthetic.h"
#include "tests/core/mesh_fixtures.h"
#include "worker/ba/ba_options.h"
#include "worker/ba/dvl_raycast_factor.h"
#include "worker/ba/odometry_factor.h"
#include "worker/ba/pose_block.h"
#include "worker/ba/prior_factors.h"
#include "worker/ba/reprojection_factors.h"
#include "worker/ba/surface_factor.h"

namespace keel::ba {
namespace {

using PoseManifold =
    ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>;

class FactorJacobians : public ::testing::Test {
 protected:
  Pose3 random_pose(double rotation_rad, double translation_m) {
    std::normal_distribution<double> n(0.0, 1.0);
    const Eigen::Vector3d w(n(rng_), n(rng_), n(rng_));
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(rotation_rad, w.normalized()).toRotationMatrix();
    T.translation() = translation_m * Eigen::Vector3d(n(rng_), n(rng_), n(rng_));
    return T;
  }

  // Central differences on the manifolds (x (+) +-h e_k, tangent space) against the factor's
  // Jacobian mapped to the tangent space by PlusJacobian. manifolds[i] == nullptr: Euclidean.
  // Entries must agree to `tolerance` relative to the block's largest entry (at least 1).
  void expect_jacobians_match(ceres::CostFunction* factor, std::vector<double*> blocks,
                              std::vector<const ceres::Manifold*> manifolds,
                              double tolerance = 1e-6) {
    std::unique_ptr<ceres::CostFunction> owned(factor);
    const int m = factor->num_residuals();
    const std::vector<int32_t>& sizes = factor->parameter_block_sizes();
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J;
    std::vector<double*> J_ptr;
    for (int32_t n : sizes) J.emplace_back(m, n);
    for (auto& j : J) J_ptr.push_back(j.data());
    Eigen::VectorXd r(m), r_plus(m), r_minus(m);
    ASSERT_TRUE(factor->Evaluate(blocks.data(), r.data(), J_ptr.data()));
    const double h = 1e-6;
    for (size_t b = 0; b < blocks.size(); ++b) {
      const int ambient = sizes[b];
      const int tangent = manifolds[b] ? manifolds[b]->TangentSize() : ambient;
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> lift(ambient, tangent);
      if (manifolds[b]) {
        manifolds[b]->PlusJacobian(blocks[b], lift.data());
      } else {
        lift.setIdentity();
      }
      const Eigen::MatrixXd analytic = J[b] * lift;
      Eigen::MatrixXd numeric(m, tangent);
      const std::vector<double> x0(blocks[b], blocks[b] + ambient);
      for (int k = 0; k < tangent; ++k) {
        Eigen::VectorXd delta = Eigen::VectorXd::Zero(tangent);
        for (double sign : {1.0, -1.0}) {
          delta[k] = sign * h;
          if (manifolds[b]) {
            manifolds[b]->Plus(x0.data(), delta.data(), blocks[b]);
          } else {
            for (int i = 0; i < ambient; ++i) blocks[b][i] = x0[i] + delta[i];
          }
          ASSERT_TRUE(
              factor->Evaluate(blocks.data(), sign > 0 ? r_plus.data() : r_minus.data(), nullptr));
        }
        std::copy(x0.begin(), x0.end(), blocks[b]);
        numeric.col(k) = (r_plus - r_minus) / (2 * h);
      }
      const double scale = std::max(1.0, analytic.cwiseAbs().maxCoeff());
      EXPECT_LE((analytic - numeric).cwiseAbs().maxCoeff(), tolerance * scale)
          << "block " << b << "\nanalytic\n"
          << analytic << "\nnumeric\n"
          << numeric;
    }
  }

  std::mt19937 rng_{42};
  PoseManifold pose_manifold_;
};

TEST_F(FactorJacobians, PosePriorEq8) {
  for (int trial = 0; trial < 5; ++trial) {
    const Pose3 prior = random_pose(0.5, 2.0);
    PoseBlock x = to_pose_block(prior * random_pose(0.2, 0.3));
    expect_jacobians_match(make_pose_prior_factor(prior, 0.1, 0.02), {x.data()}, {&pose_manifold_});
  }
}

TEST_F(FactorJacobians, DepthPitchRollEq9) {
  for (int trial = 0; trial < 5; ++trial) {
    PoseBlock x = to_pose_block(random_pose(0.6, 3.0));
    const DepthPitchRoll measured{0.3, 0.1, -0.05};
    expect_jacobians_match(make_depth_pitch_roll_factor(measured, 0.1, 0.002, 0.002), {x.data()},
                           {&pose_manifold_});
  }
}

TEST_F(FactorJacobians, ServoAngleEq10) {
  double theta = 0.07;
  expect_jacobians_match(make_servo_angle_factor(0.02, 0.087), {&theta}, {nullptr});
}

TEST_F(FactorJacobians, OdometryEq11) {
  for (int trial = 0; trial < 5; ++trial) {
    const Pose3 Ti = random_pose(1.0, 5.0);
    const Pose3 Tij = random_pose(0.3, 1.0);
    PoseBlock xi = to_pose_block(Ti), xj = to_pose_block(Ti * Tij * random_pose(0.05, 0.05));
    const OdometrySigmas sigmas = odometry_sigmas(2.0, 0.005, 80.0 * kDegToRad / 3600, 1e-4, 1e-5);
    expect_jacobians_match(make_odometry_factor(Tij, sigmas), {xi.data(), xj.data()},
                           {&pose_manifold_, &pose_manifold_});
  }
}

// A camera state looking at a landmark 1.5 m in front of it.
struct CameraState {
  PoseBlock vehicle, extrinsic;
  double theta;
  Eigen::Vector3d landmark;
};

class ReprojectionJacobians : public FactorJacobians {
 protected:
  CameraState state() {
    CameraState s;
    const Pose3 T_world_vehicle = random_pose(0.8, 3.0);
    s.theta = 0.05;
    const Pose3 T_servo_camera = random_pose(0.05, 0.1);
    s.vehicle = to_pose_block(T_world_vehicle);
    s.extrinsic = to_pose_block(T_servo_camera);
    const Pose3 T_world_camera =
        world_camera_pose(T_world_vehicle, s.theta, mount_, T_servo_camera);
    s.landmark = T_world_camera * Eigen::Vector3d(0.2, -0.1, 1.5);
    return s;
  }
  ServoMount mount_{make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())),
                              Eigen::Vector3d(0.4, 0.0, 0.2)),
                    Eigen::Vector3d::UnitY()};
  PinholeCamera camera_{800, 810, 320, 240, 640, 480};
};

TEST_F(ReprojectionJacobians, MonocularEq13) {
  for (int trial = 0; trial < 5; ++trial) {
    CameraState s = state();
    expect_jacobians_match(make_monocular_factor(camera_, mount_, Eigen::Vector2d(300, 250), 2.0),
                           {s.vehicle.data(), &s.theta, s.extrinsic.data(), s.landmark.data()},
                           {&pose_manifold_, nullptr, &pose_manifold_, nullptr});
  }
}

TEST_F(ReprojectionJacobians, StereoEq12) {
  Pose3 T_top_bottom = Pose3::Identity();
  T_top_bottom.translation() = Eigen::Vector3d(0.0, 0.1, 0.0);
  for (int trial = 0; trial < 5; ++trial) {
    CameraState s = state();
    expect_jacobians_match(
        make_stereo_factor(camera_, camera_, T_top_bottom, mount_, Eigen::Vector2d(300, 250),
                           Eigen::Vector2d(301, 190), 2.0),
        {s.vehicle.data(), &s.theta, s.extrinsic.data(), s.landmark.data()},
        {&pose_manifold_, nullptr, &pose_manifold_, nullptr});
  }
}

TEST_F(FactorJacobians, DvlRaycastEq14) {
  testing::SyntheticHullOptions hull;
  const MeshQuery mesh(testing::make_hull_patch(hull, true));  // bumpy: normals vary
  const ServoMount mount{make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.4, 0, 0.2)),
                         Eigen::Vector3d::UnitY()};
  Pose3 T_servo_dvl = Pose3::Identity();
  T_servo_dvl.translation() = Eigen::Vector3d(-0.1, 0, 0.1);
  int probed = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T_world_model = random_pose(0.1, 1.0);
    const Pose3 T_model_vehicle =
        make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.2 * trial / 20.0, 0.1, -1.5));
    PoseBlock vehicle = to_pose_block(T_world_model * T_model_vehicle * random_pose(0.05, 0.05));
    PoseBlock model = to_pose_block(T_world_model);
    double theta = 0.04;
    const Eigen::Vector3d direction = Eigen::Vector3d(0.35, -0.35, 0.87).normalized();
    const DvlBeam beam = make_dvl_beam(T_servo_dvl, direction, 1.6);
    ASSERT_TRUE(predict_dvl_range(mesh, mount, beam, from_pose_block(vehicle.data()), theta,
                                  T_world_model, 30.0));
    // kFacet: the exact derivative of the facet range (the default linearises with the smooth
    // surface's normal instead; dvl_raycast_test.cc checks that against a sphere).
    expect_jacobians_match(
        make_dvl_raycast_factor(mesh, mount, beam, 0.003, 30.0, 0.5, DvlRangeNormal::kFacet),
        {vehicle.data(), &theta, model.data()}, {&pose_manifold_, nullptr, &pose_manifold_}, 1e-5);
    ++probed;
  }
  EXPECT_EQ(probed, 20);
}

// The default (interpolated) normal is the facet's on flat faces up to a crease: on a box the
// smooth linearisation is the exact derivative, also for beams hitting next to an edge.
TEST_F(FactorJacobians, DvlRaycastInterpolatedNormalIsExactOnABox) {
  const MeshQuery mesh(testing::make_box({-1.0, -1.0, 1.0}, {1.0, 1.0, 2.0}));
  const ServoMount mount{make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.4, 0, 0.2)),
                         Eigen::Vector3d::UnitY()};
  for (int trial = 0; trial < 20; ++trial) {
    // Beams at the box's underside, hitting 2-4 cm from its y = 1 edge, x from 0.5 to 0.98.
    PoseBlock vehicle = to_pose_block(make_pose(Eigen::Quaterniond::Identity(),
                                                Eigen::Vector3d(0.025 * trial - 0.42, 0.52, -0.5)) *
                                      random_pose(0.002, 0.01));
    PoseBlock model = to_pose_block(Pose3::Identity());
    double theta = 0.0;
    const Eigen::Vector3d direction = Eigen::Vector3d(0.35, 0.3, 0.87).normalized();
    const DvlBeam beam = make_dvl_beam(Pose3::Identity(), direction, 1.6);
    ASSERT_TRUE(predict_dvl_range(mesh, mount, beam, from_pose_block(vehicle.data()), theta,
                                  Pose3::Identity(), 30.0));
    expect_jacobians_match(make_dvl_raycast_factor(mesh, mount, beam, 0.003, 30.0, 0.5),
                           {vehicle.data(), &theta, model.data()},
                           {&pose_manifold_, nullptr, &pose_manifold_}, 1e-5);
  }
}

// Landmarks at `offset` along the normal from a face's centroid (face region) and from a
// grid vertex (vertex region, outside only: the solid is convex, so inside a vertex every
// point is on the medial axis, where the distance has no derivative).
TEST_F(FactorJacobians, SurfaceEq5BothComponentsAndModes) {
  testing::SyntheticHullOptions hull;
  const TriangleMesh patch = testing::make_hull_patch(hull, false);
  const MeshQuery mesh(patch);
  const MaxMixture mixture{1.0, 0.02};
  const auto face_near = [&](const Eigen::Vector2d& xy) {
    Eigen::Vector3d best_centroid, best_normal;
    double best = 1e9;
    for (const auto& f : patch.faces) {
      const Eigen::Vector3d a = patch.vertices[f[0]], b = patch.vertices[f[1]],
                            c = patch.vertices[f[2]];
      const Eigen::Vector3d centroid = (a + b + c) / 3.0;
      if ((centroid.head<2>() - xy).norm() < best) {
        best = (centroid.head<2>() - xy).norm();
        best_centroid = centroid;
        best_normal = (b - a).cross(c - a).normalized();
      }
    }
    return std::pair{best_centroid, best_normal};
  };
  struct Case {
    Eigen::Vector3d point, normal;
    std::vector<double> offsets;  // below and above the 5.6 cm switch: both components
  };
  const auto [centroid_a, normal_a] = face_near({-0.913, 0.377});
  const auto [centroid_b, normal_b] = face_near({1.2, -0.6});
  // The grid vertex at (-1, 0.5), approached along the analytic surface normal.
  const Eigen::Vector3d grid_vertex(-1.0, 0.5, hull.curvature_x + 0.25 * hull.curvature_y);
  const Eigen::Vector3d analytic_normal =
      Eigen::Vector3d(-2.0 * hull.curvature_x, 2.0 * hull.curvature_y * 0.5, -1.0).normalized();
  const ClosestPoint vertex = mesh.closest_point(grid_vertex + 0.01 * analytic_normal);
  ASSERT_EQ(vertex.feature, MeshFeature::kVertex);
  ASSERT_LT((vertex.point - grid_vertex).norm(), 1e-9);
  const Case cases[] = {{centroid_a, normal_a, {0.01, -0.03, 0.2, -0.4}},
                        {centroid_b, normal_b, {-0.01, 0.03, -0.2, 0.4}},
                        {vertex.point, vertex.normal, {0.01, 0.04, 0.2, 0.5}}};
  for (const Case& c : cases) {
    for (double offset : c.offsets) {
      for (SurfaceMode mode : {SurfaceMode::kMaxMixture, SurfaceMode::kOnModel}) {
        const Pose3 T_world_model = random_pose(0.2, 1.0);
        Eigen::Vector3d landmark = T_world_model * (c.point + offset * c.normal);
        PoseBlock model = to_pose_block(T_world_model);
        expect_jacobians_match(make_surface_factor(mesh, mixture, mode, 0.0),
                               {model.data(), landmark.data()}, {&pose_manifold_, nullptr}, 1e-5);
      }
    }
  }
}

}  // namespace
}  // namespace keel::ba
