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
#include "tests/core/mesh_fixtures.h"
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
    // Fig. 18(a)-(b)'s hit point: along the beam, at the brute-force range, in the model frame.
    const auto hit =
        predict_dvl_hit(query, mount, beam, T_world_vehicle, theta, T_world_model, 30.0);
    ASSERT_TRUE(hit.has_value()) << "trial " << trial;
    const Eigen::Vector3d expected_point =
        T_model_dvl.translation() + *expected * (T_model_dvl.linear() * direction_dvl);
    EXPECT_LT((hit->point_model - expected_point).norm(), 1e-9) << "trial " << trial;
    EXPECT_EQ(hit->range_m, *predicted);
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

// The factor at a beam from `origin` (vehicle at `origin`, identity mount and model): its
// residual and d range / d origin (r = (measured - range) / sigma, and the vehicle block's
// translation moves the beam origin).
struct RangeSlope {
  double residual;
  Eigen::Vector3d gradient;
};
RangeSlope range_slope(const MeshQuery& mesh, const DvlBeam& beam, const Eigen::Vector3d& origin,
                       DvlRangeNormal normal) {
  const ServoMount mount{Pose3::Identity(), Eigen::Vector3d::UnitX()};
  PoseBlock vehicle = to_pose_block(make_pose(Eigen::Quaterniond::Identity(), origin));
  PoseBlock model = to_pose_block(Pose3::Identity());
  double theta = 0;
  double* blocks[3] = {vehicle.data(), &theta, model.data()};
  std::unique_ptr<ceres::CostFunction> f(
      make_dvl_raycast_factor(mesh, mount, beam, 0.003, 30.0, 0.5, normal));
  double r = 0, J_vehicle[kPoseBlockSize], J_theta[1], J_model[kPoseBlockSize];
  double* jacobians[3] = {J_vehicle, J_theta, J_model};
  EXPECT_TRUE(f->Evaluate(blocks, &r, jacobians));
  return {r, -0.003 * Eigen::Vector3d(J_vehicle[4], J_vehicle[5], J_vehicle[6])};
}

// Range from o along unit d to the sphere |x - c| = R (closed form), nullopt on a miss.
std::optional<double> sphere_range(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double R) {
  const double b = d.dot(o), c = o.squaredNorm() - R * R;
  if (b * b - c < 0) return std::nullopt;
  return -b - std::sqrt(b * b - c);
}

// The default linearisation follows the smooth surface the facets sample: on an icosphere of
// radius 4 m with ~0.27 m edges (the keel-sim hull's CAD mesh has a 0.26 m median edge), the
// factor's derivative w.r.t. the vehicle position matches the true sphere's range gradient
// (central differences of the closed form) several times better than the facet derivative.
TEST(DvlRaycast, InterpolatedNormalLinearisesTheSmoothSurface) {
  const double radius = 4.0;
  const MeshQuery mesh(testing::make_icosphere(4, radius));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  double facet_error = 0, interpolated_error = 0;
  int beams = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3d origin = Eigen::Vector3d(u(rng), u(rng), -5.5);  // below the sphere
    const Eigen::Vector3d direction = Eigen::Vector3d(0.4 * u(rng), 0.4 * u(rng), 1).normalized();
    if (!sphere_range(origin, direction, radius)) continue;
    Eigen::Vector3d truth;  // d range / d origin of the smooth sphere
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d step = 1e-6 * Eigen::Vector3d::Unit(k);
      truth[k] = (*sphere_range(origin + step, direction, radius) -
                  *sphere_range(origin - step, direction, radius)) /
                 2e-6;
    }
    const DvlBeam beam = make_dvl_beam(Pose3::Identity(), direction, 1.5);
    facet_error +=
        (range_slope(mesh, beam, origin, DvlRangeNormal::kFacet).gradient - truth).norm();
    interpolated_error +=
        (range_slope(mesh, beam, origin, DvlRangeNormal::kInterpolated).gradient - truth).norm();
    ++beams;
  }
  ASSERT_GT(beams, 200);
  EXPECT_LT(interpolated_error, 0.25 * facet_error)
      << "mean gradient error: facet " << facet_error / beams << ", interpolated "
      << interpolated_error / beams;
  EXPECT_LT(interpolated_error / beams, 0.01);
}

// A flat face A next to a face B tilted 25 degrees (a smooth edge): near the edge A's smooth
// normal leans ~12 degrees towards B's, so a beam hitting A at ~77 degrees runs nearly
// parallel to the smooth plane. The linearisation must then fall back to the facet normal:
// never a "miss", and never more than twice the facet derivative (1 / |n.d|).
TEST(DvlRaycast, SteepBeamsNearASmoothEdgeKeepABoundedDerivative) {
  const double rise = 2.0 * std::tan(25.0 * M_PI / 180.0);
  TriangleMesh roof;
  roof.vertices = {{-2, 0, 1}, {2, 0, 1}, {0, -2, 1}, {0, 2, 1 + rise}};
  roof.faces = {{0, 1, 2}, {1, 0, 3}};  // both facing down, to the beams
  const MeshQuery mesh(roof);
  int beams = 0;
  for (int k = 0; k <= 400; ++k) {
    const double incidence = (60.0 + 25.0 * k / 400.0) * M_PI / 180.0;  // ranges up to 11.5 m
    const Eigen::Vector3d direction(0, std::sin(incidence), std::cos(incidence));
    const double y_hit = -0.05;  // on A, 5 cm from the edge
    const Eigen::Vector3d origin(0.1, y_hit - std::tan(incidence), 0.0);
    const DvlBeam beam = make_dvl_beam(Pose3::Identity(), direction, 1.0);
    double slope[2];
    for (const DvlRangeNormal normal : {DvlRangeNormal::kFacet, DvlRangeNormal::kInterpolated}) {
      const RangeSlope at = range_slope(mesh, beam, origin, normal);
      ASSERT_NE(at.residual, 0.5 / 0.003) << "beam at " << incidence * 180 / M_PI << " deg missed";
      slope[normal == DvlRangeNormal::kFacet ? 0 : 1] = at.gradient.norm();
    }
    EXPECT_LE(slope[1], 2.0 * slope[0] * (1 + 1e-9))
        << "at " << incidence * 180 / M_PI << " deg: facet " << slope[0] << ", smooth " << slope[1];
    ++beams;
  }
  EXPECT_EQ(beams, 401);
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
