// The self-check on cases with known answers: refined poses displaced from the MAP by chosen
// amounts, against chosen MAP noise, give the movements, Mahalanobis distances and flags
// computed here by hand.
#include "worker/slam/map_agreement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

Trajectory straight_run(int n) {
  Trajectory t;
  for (int k = 0; k < n; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(k, 0.0, 0.0);
    T.linear() = so3_exp(Eigen::Vector3d(0.0, 0.0, 0.1 * k));
    t.push_back({TimeNs(k) * 1000000000, T});
  }
  return t;
}

TEST(MapAgreement, MovementsDistancesAndFlagsAsComputedByHand) {
  const Trajectory map = straight_run(6);
  Trajectory refined = map;
  // Keyframe 1: 0.02 m along y (2 sigma of 1 cm white noise): not flagged.
  refined[1].T_world_body.translation() += Eigen::Vector3d(0.0, 0.02, 0.0);
  // Keyframe 2: 0.1 m along x (10 sigma): flagged.
  refined[2].T_world_body.translation() += Eigen::Vector3d(0.1, 0.0, 0.0);
  // Keyframe 3: turned 0.05 rad about body z (5 sigma of 0.01 rad): flagged.
  refined[3].T_world_body.linear() =
      map[3].T_world_body.linear() * so3_exp(Eigen::Vector3d(0.0, 0.0, 0.05));
  // Keyframe 5: 0.3 m along x after 100 m of drift path at 0.01 m/sqrt(m): sigma =
  // sqrt(0.01^2 + 0.01^2 * 100) = 0.1005 m, 2.985 sigma: inside the 3.76-sigma threshold.
  refined[5].T_world_body.translation() += Eigen::Vector3d(0.3, 0.0, 0.0);
  const MapPoseNoise noise = MapPoseNoise::isotropic(0.01, 0.01, 0.01);
  const std::vector<double> drift_path = {0.0, 0.0, 0.0, 0.0, 0.0, 100.0};
  const MapAgreement a = compare_with_map(map, refined, noise, drift_path);

  ASSERT_EQ(a.keyframes.size(), 6u);
  EXPECT_NEAR(a.keyframes[1].mahalanobis_translation, 2.0, 1e-9);
  EXPECT_NEAR(a.keyframes[2].mahalanobis_translation, 10.0, 1e-9);
  EXPECT_NEAR(a.keyframes[3].mahalanobis_rotation, 5.0, 1e-9);
  EXPECT_NEAR(a.keyframes[3].rotation_rad.z(), 0.05, 1e-12);
  EXPECT_NEAR(a.keyframes[5].mahalanobis_translation, 0.3 / std::sqrt(0.0001 + 0.01), 1e-9);
  EXPECT_NEAR(a.keyframes[5].translation_m.x(), 0.3, 1e-12);
  EXPECT_EQ(a.keyframes[5].drift_path_m, 100.0);
  const std::vector<bool> flagged = {false, false, true, true, false, false};
  for (size_t k = 0; k < flagged.size(); ++k) EXPECT_EQ(a.keyframes[k].flagged, flagged[k]) << k;
  EXPECT_EQ(a.flagged, 2);
  EXPECT_EQ(a.keyframes[4].mahalanobis_translation, 0.0);
  // Totals: translations 0.02, 0.1 and 0.3 m over 6 keyframes; one rotation of 0.05 rad.
  EXPECT_NEAR(a.translation_rms_m, std::sqrt((0.02 * 0.02 + 0.1 * 0.1 + 0.3 * 0.3) / 6.0), 1e-12);
  EXPECT_NEAR(a.translation_max_m, 0.3, 1e-12);
  EXPECT_NEAR(a.rotation_rms_rad, 0.05 / std::sqrt(6.0), 1e-12);
  EXPECT_NEAR(a.rotation_max_rad, 0.05, 1e-12);
}

// A correlated (non-isotropic) covariance: the same displacement is far along the short axis
// and near along the long one.
TEST(MapAgreement, UsesTheFullCovariance) {
  const Trajectory map = straight_run(2);
  MapPoseNoise noise = MapPoseNoise::isotropic(0.01, 0.01, 0.0);
  noise.translation_covariance = Eigen::Vector3d(0.25, 0.0001, 0.0001).asDiagonal();  // 0.5 m, 1 cm
  Trajectory along = map, across = map;
  along[1].T_world_body.translation() += Eigen::Vector3d(0.5, 0.0, 0.0);
  across[1].T_world_body.translation() += Eigen::Vector3d(0.0, 0.5, 0.0);
  const std::vector<double> path = {0.0, 0.0};
  EXPECT_NEAR(compare_with_map(map, along, noise, path).keyframes[1].mahalanobis_translation, 1.0,
              1e-9);
  EXPECT_NEAR(compare_with_map(map, across, noise, path).keyframes[1].mahalanobis_translation, 50.0,
              1e-9);
  EXPECT_FALSE(compare_with_map(map, along, noise, path).keyframes[1].flagged);
  EXPECT_TRUE(compare_with_map(map, across, noise, path).keyframes[1].flagged);
}

TEST(MapAgreement, RejectsMismatchedKeyframes) {
  const Trajectory map = straight_run(3);
  Trajectory shifted = map;
  shifted[1].t_ns += 1;
  const MapPoseNoise noise = MapPoseNoise::isotropic(0.01, 0.01, 0.0);
  EXPECT_THROW(compare_with_map(map, shifted, noise, {0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(compare_with_map(map, map, noise, {0, 0}), std::invalid_argument);
  EXPECT_THROW(compare_with_map(map, map, MapPoseNoise{}, {0, 0, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace keel::slam
