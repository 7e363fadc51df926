// refine_extrinsic on synthetic scenes of rectangles with known extrinsics: a box room (every
// direction observable), a corridor (translation along its axis is not), no overlap.
#include "worker/mapping/extrinsic_refinement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace keel::mapping {
namespace {

struct Rectangle {
  Eigen::Vector3d center, u, v;  // u, v: half-extent vectors
};

Eigen::Isometry3d pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}
Eigen::Matrix3d rot(const Eigen::Vector3d& axis, double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

// One scan: points drawn uniformly on the rectangles (density per m^2), those within range_m
// of the sensor, in the sensor frame, with isotropic noise.
PlacedScan scan(const std::vector<Rectangle>& scene, const Eigen::Isometry3d& T_world_body,
                const Eigen::Isometry3d& T_body_sensor, double range_m, std::mt19937& rng,
                double density = 20.0, double noise_m = 0.003) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, noise_m);
  const Eigen::Isometry3d T_world_sensor = T_world_body * T_body_sensor;
  const Eigen::Isometry3d T_sensor_world = T_world_sensor.inverse();
  PlacedScan out;
  out.T_world_body = T_world_body;
  for (const Rectangle& r : scene) {
    const int n = static_cast<int>(density * 4.0 * r.u.norm() * r.v.norm());
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = r.center + uniform(rng) * r.u + uniform(rng) * r.v;
      if ((p - T_world_sensor.translation()).norm() > range_m) continue;
      const Eigen::Vector3d noise(gauss(rng), gauss(rng), gauss(rng));
      out.points.push_back((T_sensor_world * p + noise).cast<float>());
    }
  }
  return out;
}

double angle_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

const Eigen::Isometry3d kBodyReference = pose(Eigen::Matrix3d::Identity(), {0.3, 0.0, 1.0});
// A vertical lidar: spin axis forward, as keel-sim's usv rig has it.
const Eigen::Isometry3d kReferenceCandidateTrue = pose(rot({0, 1, 0}, 90.0), {0.2, 0.0, 0.2});
// 2 deg about a skew axis and 5 cm.
const Eigen::Isometry3d kError =
    pose(rot({1, -2, 0.5}, 2.0), Eigen::Vector3d(3, -2, 3).normalized() * 0.05);

struct Scans {
  std::vector<PlacedScan> reference, candidate;
};

Scans simulate(const std::vector<Rectangle>& scene, const std::vector<Eigen::Isometry3d>& bodies,
               double range_m, unsigned seed) {
  std::mt19937 rng(seed);
  Scans out;
  const Eigen::Isometry3d T_body_candidate = kBodyReference * kReferenceCandidateTrue;
  for (const Eigen::Isometry3d& T_world_body : bodies) {
    out.reference.push_back(scan(scene, T_world_body, kBodyReference, range_m, rng));
    out.candidate.push_back(scan(scene, T_world_body, T_body_candidate, range_m, rng));
  }
  return out;
}

TEST(ExtrinsicRefinement, BoxRoomRecoversTwoDegreesAndFiveCentimetres) {
  // Floor, ceiling and two pairs of walls of a 12 x 8 x 4 m room.
  const std::vector<Rectangle> room = {
      {{0, 0, -1}, {6, 0, 0}, {0, 4, 0}}, {{0, 0, 3}, {6, 0, 0}, {0, 4, 0}},
      {{0, 4, 1}, {6, 0, 0}, {0, 0, 2}},  {{0, -4, 1}, {6, 0, 0}, {0, 0, 2}},
      {{6, 0, 1}, {0, 4, 0}, {0, 0, 2}},  {{-6, 0, 1}, {0, 4, 0}, {0, 0, 2}}};
  std::vector<Eigen::Isometry3d> bodies;
  for (int i = 0; i < 10; ++i)
    bodies.push_back(pose(rot({0, 0, 1}, -30.0 + 6.0 * i), {-3.0 + 0.6 * i, 0.5 * std::sin(i), 0}));
  const Scans scans = simulate(room, bodies, 9.0, 1);
  const Eigen::Isometry3d initial = kReferenceCandidateTrue * kError;

  const ExtrinsicRefinementResult result = refine_extrinsic(
      scans.reference, scans.candidate, kBodyReference, initial, "lidar_h", "lidar_v");

  ASSERT_FALSE(result.refused) << result.reason;
  EXPECT_TRUE(result.converged);
  EXPECT_LT(angle_deg(result.T_reference_candidate, kReferenceCandidateTrue), 0.05);
  EXPECT_LT(
      (result.T_reference_candidate.translation() - kReferenceCandidateTrue.translation()).norm(),
      0.002);
  EXPECT_TRUE(result.unobservable.empty());
  // The residual spread is the noise across a plane: 3 mm per axis, the plane fit's own
  // noise added (sqrt(1 + 1/k) for k ~ 10).
  EXPECT_GT(result.residual_sigma_m, 0.002);
  EXPECT_LT(result.residual_sigma_m, 0.005);
  EXPECT_LT(result.after.median_m, 0.5 * result.before.median_m);
  // Covariance: positive, and the translation sigmas below a millimetre with ~10^5 points.
  for (int i = 0; i < 6; ++i) EXPECT_GT(result.covariance(i, i), 0.0);
  EXPECT_LT(std::sqrt(result.covariance.diagonal().head<3>().maxCoeff()), 0.001);
}

TEST(ExtrinsicRefinement, CorridorLeavesTheAxisTranslationUnchanged) {
  // Two parallel walls and a floor along x; the body drives along x without turning.
  const std::vector<Rectangle> corridor = {{{0, 3.5, 1}, {60, 0, 0}, {0, 0, 2}},
                                           {{0, -3.5, 1}, {60, 0, 0}, {0, 0, 2}},
                                           {{0, 0, -1}, {60, 0, 0}, {0, 3.5, 0}}};
  std::vector<Eigen::Isometry3d> bodies;
  for (int i = 0; i < 12; ++i)
    bodies.push_back(pose(Eigen::Matrix3d::Identity(), {-12.0 + 2.0 * i, 0.4 * std::sin(i), 0}));
  const Scans scans = simulate(corridor, bodies, 10.0, 2);
  const Eigen::Isometry3d initial = kReferenceCandidateTrue * kError;

  const ExtrinsicRefinementResult result = refine_extrinsic(
      scans.reference, scans.candidate, kBodyReference, initial, "lidar_h", "lidar_v");

  ASSERT_FALSE(result.refused) << result.reason;
  ASSERT_EQ(result.unobservable.size(), 1u);
  // The direction is a translation along the corridor: x of the reference frame (the body
  // never turns and T_body_reference does not rotate).
  const Vector6d& d = result.unobservable[0].direction;
  EXPECT_LT(d.tail<3>().norm(), 1e-3);
  const Eigen::Vector3d in_reference = initial.linear() * d.head<3>();
  EXPECT_GT(std::abs(in_reference.x()), 0.999);
  // Unchanged along it; recovered across it and in rotation.
  const Eigen::Vector3d t = result.T_reference_candidate.translation();
  EXPECT_NEAR(t.x(), initial.translation().x(), 1e-4);
  EXPECT_NEAR(t.y(), kReferenceCandidateTrue.translation().y(), 0.002);
  EXPECT_NEAR(t.z(), kReferenceCandidateTrue.translation().z(), 0.002);
  EXPECT_LT(angle_deg(result.T_reference_candidate, kReferenceCandidateTrue), 0.05);
  // Its variance is far larger than the observable ones'.
  EXPECT_GT(d.dot(result.covariance * d), 1e3 * result.covariance(1, 1));
}

TEST(ExtrinsicRefinement, CauchyLossGivesTheSameEstimateOnAnyThreadCount) {
  const std::vector<Rectangle> room = {{{0, 0, -1}, {5, 0, 0}, {0, 4, 0}},
                                       {{0, 4, 1}, {5, 0, 0}, {0, 0, 2}},
                                       {{5, 0, 1}, {0, 4, 0}, {0, 0, 2}},
                                       {{0, -4, 1}, {5, 0, 0}, {0, 0, 2}}};
  std::vector<Eigen::Isometry3d> bodies;
  for (int i = 0; i < 5; ++i)
    bodies.push_back(pose(rot({0, 0, 1}, 10.0 * i), {-2.0 + i, 0.3 * i, 0}));
  const Scans scans = simulate(room, bodies, 9.0, 4);
  ExtrinsicRefinementOptions options;
  options.loss = RobustLoss::kCauchy;
  options.threads = 1;
  const auto one =
      refine_extrinsic(scans.reference, scans.candidate, kBodyReference,
                       kReferenceCandidateTrue * kError, "lidar_h", "lidar_v", options);
  options.threads = 3;
  const auto three =
      refine_extrinsic(scans.reference, scans.candidate, kBodyReference,
                       kReferenceCandidateTrue * kError, "lidar_h", "lidar_v", options);
  ASSERT_FALSE(one.refused) << one.reason;
  EXPECT_LT(angle_deg(one.T_reference_candidate, kReferenceCandidateTrue), 0.05);
  EXPECT_LT(
      (one.T_reference_candidate.translation() - kReferenceCandidateTrue.translation()).norm(),
      0.002);
  EXPECT_EQ(one.T_reference_candidate.matrix(), three.T_reference_candidate.matrix());
  EXPECT_EQ(one.covariance, three.covariance);
}

TEST(ExtrinsicRefinement, CandidateWithoutOverlapIsRefusedNamingBothSensors) {
  const std::vector<Rectangle> floor = {{{0, 0, -1}, {10, 0, 0}, {0, 10, 0}}};
  const std::vector<Rectangle> elsewhere = {{{200, 0, -1}, {10, 0, 0}, {0, 10, 0}}};
  std::mt19937 rng(3);
  std::vector<PlacedScan> reference, candidate;
  const Eigen::Isometry3d T_body_candidate = kBodyReference * kReferenceCandidateTrue;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Isometry3d body = pose(Eigen::Matrix3d::Identity(), {i * 1.0, 0, 0});
    reference.push_back(scan(floor, body, kBodyReference, 15.0, rng));
    // The candidate's data come from a far-away floor: nothing of it is near the map.
    PlacedScan c = scan(elsewhere, pose(Eigen::Matrix3d::Identity(), {200.0 + i, 0, 0}),
                        T_body_candidate, 15.0, rng);
    c.T_world_body = body;
    candidate.push_back(c);
  }
  for (auto& c : candidate)
    for (auto& p : c.points) p += Eigen::Vector3f(0, 0, 30);  // and 30 m off its plane
  const ExtrinsicRefinementResult result = refine_extrinsic(
      reference, candidate, kBodyReference, kReferenceCandidateTrue, "lidar_h", "sonar");
  EXPECT_TRUE(result.refused);
  EXPECT_NE(result.reason.find("'sonar'"), std::string::npos) << result.reason;
  EXPECT_NE(result.reason.find("'lidar_h'"), std::string::npos) << result.reason;
  EXPECT_TRUE(result.T_reference_candidate.isApprox(kReferenceCandidateTrue));
}

TEST(ExtrinsicRefinement, RightPerturbationIsInTheCandidateFrame) {
  const Eigen::Isometry3d T = pose(rot({0, 0, 1}, 90.0), {1, 2, 3});
  Vector6d delta;
  delta << 1, 0, 0, 0, 0, 0;
  // +x of the candidate is +y of the reference after a 90 deg yaw.
  EXPECT_TRUE(apply_right_perturbation(T, delta).translation().isApprox(Eigen::Vector3d(1, 3, 3)));
}

}  // namespace
}  // namespace keel::mapping
