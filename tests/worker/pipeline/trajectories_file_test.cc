// trajectories.json: per-pose ATE whose root mean square is the report's ATE RMSE (same
// association, same alignment), zero for an estimate that is the truth moved rigidly, NaN (null)
// where no ground-truth pose associates; the file keeps the entries of earlier stages.
#include "worker/pipeline/trajectories_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>

#include <cmath>
#include <fstream>

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

Pose3 pose(double x, double y, double z, double yaw) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

// 10 Hz ground truth on a curve, 20 s.
Trajectory truth() {
  Trajectory t;
  for (int i = 0; i <= 200; ++i) {
    const double s = 0.1 * i;
    t.push_back({seconds_to_ns(1000.0 + s), pose(s, 2.0 * std::sin(0.3 * s), 0.1 * s, 0.3 * s)});
  }
  return t;
}

// Every 10th truth pose moved by `T_offset`, plus a deterministic wobble of `wobble_m`.
Trajectory keyframes(const Pose3& T_offset, double wobble_m) {
  const Trajectory t = truth();
  Trajectory out;
  for (size_t i = 0; i < t.size(); i += 10) {
    Pose3 T = T_offset * t[i].T_world_body;
    T.translation() +=
        wobble_m * Eigen::Vector3d(std::sin(1.7 * i), std::cos(2.3 * i), std::sin(0.9 * i));
    out.push_back({t[i].t_ns, T});
  }
  return out;
}

TEST(PerPoseAte, RootMeanSquareIsTheReportsAteRmse) {
  slam::AssociationOptions association;
  association.max_difference_s = 0.01;
  Trajectory estimate = keyframes(pose(3.0, -1.0, 0.5, 0.4), 0.05);
  // A pose 5 s after the truth ends associates with nothing.
  estimate.push_back({estimate.back().t_ns + seconds_to_ns(5.0), estimate.back().T_world_body});
  const std::vector<double> ate = per_pose_ate(truth(), estimate, association);
  ASSERT_EQ(ate.size(), estimate.size());
  EXPECT_TRUE(std::isnan(ate.back()));
  double sum = 0;
  size_t count = 0;
  for (double e : ate)
    if (std::isfinite(e)) sum += e * e, ++count;
  const slam::AteResult report =
      slam::absolute_trajectory_error(truth(), estimate, slam::Alignment::kSE3, association);
  EXPECT_EQ(count, report.translation_m.count);
  EXPECT_NEAR(std::sqrt(sum / count), report.translation_m.rmse, 1e-12);
  EXPECT_GT(report.translation_m.rmse, 0.01);
}

TEST(PerPoseAte, RigidlyMovedTruthHasNoError) {
  const Trajectory estimate = keyframes(pose(-4.0, 7.0, 1.0, -1.1), 0.0);
  for (double e : per_pose_ate(truth(), estimate, {})) EXPECT_NEAR(e, 0.0, 1e-9);
}

TEST(TrajectoriesFile, StagesAddTheirEntriesAndReplaceTheirOwn) {
  const fs::path dir = fs::temp_directory_path() / ("keel_traj_file_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const Trajectory recorded = keyframes(Pose3::Identity(), 0.1);
  const Trajectory refined = keyframes(Pose3::Identity(), 0.01);
  add_to_trajectories_file(
      dir, {{"recorded", "world", recorded, {0.5, NAN}}, {"refined", "world", refined, {}}});
  const Pose3 T_world_model = pose(1.0, 2.0, 3.0, 0.5);
  add_to_trajectories_file(dir, {{"ba", "model", refined, {}}}, T_world_model);
  add_to_trajectories_file(dir, {{"refined", "world", recorded, {}}});  // a rerun of refine

  std::ifstream in(dir / kTrajectoriesFile);
  const json doc = json::parse(in);
  EXPECT_EQ(doc["frame"], "world");
  EXPECT_NEAR(doc["T_world_model"]["translation"][2].get<double>(), 3.0, 1e-15);
  ASSERT_EQ(doc["trajectories"].size(), 3u);
  EXPECT_EQ(doc["trajectories"][0]["name"], "recorded");
  EXPECT_EQ(doc["trajectories"][1]["name"], "ba");
  EXPECT_EQ(doc["trajectories"][1]["frame"], "model");
  EXPECT_EQ(doc["trajectories"][2]["name"], "refined");
  const json& first = doc["trajectories"][0];
  EXPECT_EQ(first["ate_m"][0], 0.5);
  EXPECT_TRUE(first["ate_m"][1].is_null());  // NaN
  EXPECT_FALSE(doc["trajectories"][2].contains("ate_m"));
  ASSERT_EQ(first["t"].size(), recorded.size());
  for (size_t i = 0; i < recorded.size(); ++i) {
    EXPECT_EQ(first["t"][i].get<double>(), ns_to_seconds(recorded[i].t_ns));
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(first["xyz"][i][c].get<double>(), recorded[i].T_world_body.translation()[c]);
  }
  // The rerun's poses replaced refine's first ones.
  EXPECT_EQ(doc["trajectories"][2]["xyz"][3][0].get<double>(),
            recorded[3].T_world_body.translation().x());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::pipeline
