#include "worker/slam/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "worker/slam/so3.h"

namespace keel::slam {
namespace {

std::vector<Pose3> random_poses(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-10, 10), a(-1, 1);
  std::vector<Pose3> out;
  for (int k = 0; k < n; ++k) {
    Pose3 T = Pose3::Identity();
    T.linear() = so3_exp(Eigen::Vector3d(a(rng), a(rng), a(rng)));
    T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
    out.push_back(T);
  }
  return out;
}

SimilarityTransform known_transform(double scale) {
  SimilarityTransform S;
  S.R = so3_exp(Eigen::Vector3d(0.4, -1.1, 2.0));
  S.t = Eigen::Vector3d(3.0, -7.0, 1.5);
  S.scale = scale;
  return S;
}

TEST(Umeyama, RecoversAKnownSe3AndSim3Exactly) {
  const auto ref = random_poses(50, 1);
  for (bool with_scale : {false, true}) {
    const SimilarityTransform truth = known_transform(with_scale ? 2.5 : 1.0);
    // est = truth^-1 applied to ref, so aligning est onto ref must return truth.
    std::vector<Eigen::Vector3d> x, y;
    for (const Pose3& T : ref) {
      y.push_back(T.translation());
      x.push_back(truth.R.transpose() * (T.translation() - truth.t) / truth.scale);
    }
    const SimilarityTransform S = umeyama_alignment(x, y, with_scale);
    EXPECT_LT((S.R - truth.R).norm(), 1e-12);
    EXPECT_LT((S.t - truth.t).norm(), 1e-10);
    EXPECT_NEAR(S.scale, truth.scale, 1e-12);
  }
}

TEST(Umeyama, RejectsDegenerateInput) {
  std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_THROW(umeyama_alignment(line, line, false), std::invalid_argument);
  EXPECT_THROW(umeyama_alignment(line, {{0, 0, 0}}, false), std::invalid_argument);
}

TEST(ErrorStatistics, MatchesHandComputedValues) {
  const ErrorStatistics s = error_statistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population std, as numpy/evo
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(error_statistics({3.0, 1.0, 2.0}).median, 2.0);
}

TEST(Ate, AlignedCopyHasZeroErrorAndUnalignedErrorIsTheOffset) {
  const auto ref = random_poses(30, 2);
  const SimilarityTransform S = known_transform(1.7);
  std::vector<Pose3> est;
  for (const Pose3& T : ref) est.push_back(S.apply(T));
  const AteResult sim3 = absolute_trajectory_error(ref, est, Alignment::kSim3);
  EXPECT_LT(sim3.translation_m.max, 1e-9);
  EXPECT_LT(sim3.rotation_deg.max, 1e-6);
  EXPECT_NEAR(sim3.alignment.scale, 1.0 / 1.7, 1e-12);
  // No alignment, est = ref shifted by (0, 0, 2) and rotated 10 deg about its own z.
  std::vector<Pose3> shifted;
  for (const Pose3& T : ref) {
    Pose3 U = T;
    U.translation() += Eigen::Vector3d(0, 0, 2);
    U.linear() = T.linear() * so3_exp(Eigen::Vector3d(0, 0, 10 * M_PI / 180));
    shifted.push_back(U);
  }
  const AteResult none = absolute_trajectory_error(ref, shifted, Alignment::kNone);
  EXPECT_NEAR(none.translation_m.rmse, 2.0, 1e-12);
  EXPECT_NEAR(none.translation_m.std, 0.0, 1e-12);
  EXPECT_NEAR(none.rotation_deg.mean, 10.0, 1e-9);
}

TEST(Association, MatchesNearestStampWithinToleranceLikeEvo) {
  Trajectory ref, est;
  for (int k = 0; k < 10; ++k) ref.push_back({k * 100'000'000LL, Pose3::Identity()});  // 10 Hz
  for (int k = 0; k < 25; ++k) est.push_back({k * 40'000'000LL + 3'000'000, Pose3::Identity()});
  AssociationOptions o;
  o.max_difference_s = 0.01;
  const Association a = associate_by_time(ref, est, o);
  // Reference 0, 200, 400, 600, 800 ms match estimate 3, 203(no: 163/203), ... by hand:
  // est stamps 3 + 40 k ms; |ref - est| <= 10 ms for ref 0 (3), 200 (203), 400 (403),
  // 600 (603), 800 (803); ref 100 -> nearest 83 or 123 (17, 23 ms): no.
  ASSERT_EQ(a.reference_index.size(), 5u);
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(a.reference_index[k], 2 * k);
    EXPECT_EQ(a.estimate_index[k], 5 * k);
  }
  o.time_offset_s = -0.003;  // shifts the estimate onto the reference grid exactly
  o.max_difference_s = 1e-6;
  EXPECT_EQ(associate_by_time(ref, est, o).reference_index.size(), 5u);
}

TEST(Rpe, IsZeroForAGloballyMovedCopyAndSeesALocalJump) {
  const auto ref = random_poses(20, 3);
  const SimilarityTransform S = known_transform(1.0);
  std::vector<Pose3> est;
  for (const Pose3& T : ref) est.push_back(S.apply(T));
  RpeOptions o;
  const RpeResult r = relative_pose_error(ref, est, o);
  EXPECT_EQ(r.pairs.size(), 19u);
  EXPECT_LT(r.translation_m.max, 1e-9);
  // A jump X between indices 9 and 10 (est_k = ref_9 X ref_9^-1 ref_k for k >= 10): only the
  // pair (9, 10) sees it, with E = d^-1 X d, d = ref_9^-1 ref_10.
  Pose3 X = Pose3::Identity();
  X.translation() = Eigen::Vector3d(0.3, 0.0, 0.4);
  X.linear() = so3_exp(Eigen::Vector3d(0, 0.1, 0));
  std::vector<Pose3> jumped = ref;
  for (size_t k = 10; k < jumped.size(); ++k) jumped[k] = ref[9] * X * ref[9].inverse() * ref[k];
  const Pose3 d = ref[9].inverse() * ref[10];
  const double expected = (d.inverse() * X * d).translation().norm();
  const RpeResult j = relative_pose_error(ref, jumped, o);
  EXPECT_NEAR(j.translation_m.max, expected, 1e-9);
  EXPECT_NEAR(j.rotation_deg.max, 0.1 * 180 / M_PI, 1e-9);
  EXPECT_NEAR(j.translation_m.mean, expected / 19, 1e-9);
  EXPECT_NEAR(j.translation_m.min, 0.0, 1e-9);
  o.delta = 5;
  EXPECT_EQ(relative_pose_error(ref, est, o).pairs.size(), 3u);  // (0,5) (5,10) (10,15)
  o.all_pairs = true;
  EXPECT_EQ(relative_pose_error(ref, est, o).pairs.size(), 15u);
}

TEST(Rpe, MetreDeltasFollowThePath) {
  std::vector<Pose3> line;
  for (int k = 0; k < 21; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0.5 * k, 0, 0);  // 0.5 m steps
    line.push_back(T);
  }
  RpeOptions o;
  o.unit = DeltaUnit::kMeters;
  o.delta = 2.0;
  const RpeResult r = relative_pose_error(line, line, o);
  // Kept indices 4, 8, 12, 16, 20 -> 4 pairs (evo's filter_pairs_by_path).
  ASSERT_EQ(r.pairs.size(), 4u);
  EXPECT_EQ(r.pairs.front().first, 4u);
  EXPECT_EQ(r.pairs.front().second, 8u);
  o.all_pairs = true;
  EXPECT_EQ(relative_pose_error(line, line, o).pairs.size(), 17u);  // i = 0..16, j = i + 4
}

std::vector<Pose3> read_kitti(const std::string& path) {
  std::ifstream in(path);
  std::vector<Pose3> poses;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> M;
    for (int k = 0; k < 12; ++k) ss >> M.data()[k];
    if (!ss) break;
    Pose3 T = Pose3::Identity();
    T.linear() = M.leftCols<3>();
    T.translation() = M.col(3);
    poses.push_back(T);
  }
  return poses;
}

// Published figures for ORB-SLAM on KITTI 00 (evo_ape kitti gt est --align, translation).
TEST(Ate, KittiSequence00MatchesKnownFigures) {
  const std::string dir = std::string(KEEL_SHARED_DIR) + "/data/";
  if (!std::filesystem::exists(dir + "KITTI_00_gt.txt")) {
    GTEST_SKIP() << KEEL_SHARED_DIR << "/data/KITTI_00_*.txt absent";
  }
  const auto gt = read_kitti(dir + "KITTI_00_gt.txt");
  const auto est = read_kitti(dir + "KITTI_00_ORB.txt");
  ASSERT_EQ(gt.size(), 4541u);
  ASSERT_EQ(est.size(), gt.size());
  const AteResult r = absolute_trajectory_error(gt, est, Alignment::kSE3);
  EXPECT_NEAR(r.translation_m.rmse, 1.3034497, 1e-4);
  EXPECT_NEAR(r.translation_m.mean, 1.1569971, 1e-4);
  EXPECT_NEAR(r.translation_m.median, 1.0656248, 1e-4);
  EXPECT_NEAR(r.translation_m.std, 0.6002823, 1e-4);
  EXPECT_NEAR(r.translation_m.min, 0.0693132, 1e-4);
  EXPECT_NEAR(r.translation_m.max, 3.5879491, 1e-4);
}

}  // namespace
}  // namespace keel::slam
