// Stage `refine` on short keel-sim missions (usv-bridge, IMU + DVL only): the refined keyframes
// are closer to the simulator's ground truth than the recorded MAP poses and than the
// refinement without DVL (seed 000 Table II); option and input errors name what is wrong.
#include "worker/stages/refine/stage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/error_of.h"
#include "tests/sim/simulator.h"
#include "tests/worker/pipeline/sim_mission.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/tum.h"
#include "worker/pipeline/trajectories_file.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_refine_stage_" + std::to_string(::getpid()));
}

// One simulated mission per sensor set, shared by the tests of this file.
fs::path simulated_mission(const std::string& name, const std::vector<std::string>& sensors,
                           double dvl_scale = 1.0) {
  const fs::path dir = temp_root() / name;
  if (fs::exists(dir / "mission.yaml")) return dir;
  sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.seed = 3;
  o.out_dir = dir.string();
  o.duration_s = 60.0;
  o.sensors = sensors;
  o.dvl_scale = dvl_scale;
  sim::run_simulation(o);
  return dir;
}

using testing::StageRun;

StageRun run_stage(const fs::path& mission, const nlohmann::json& options,
                   const fs::path& work_dir) {
  return testing::run_stage(*make_refine_stage(), mission, options, work_dir);
}

double ate_rmse(const Trajectory& truth, const Trajectory& estimate) {
  return slam::absolute_trajectory_error(truth, estimate, slam::Alignment::kSE3).translation_m.rmse;
}

std::string error_of(const fs::path& mission, const nlohmann::json& options) {
  return keel::testing::error_of([&] { run_stage(mission, options, temp_root() / "work_error"); });
}

class RefineStageTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

TEST_F(RefineStageTest, RefinedKeyframesBeatMapPosesAndTheRefinementWithoutDvl) {
  const fs::path mission = simulated_mission("bridge", {"imu", "dvl"});
  const fs::path work = temp_root() / "work_bridge";
  const StageRun run = run_stage(mission, nlohmann::json::object(), work);

  // One pose per keyframe, at the keyframes' exact stamps.
  ASSERT_EQ(run.result.artifacts,
            (std::vector<std::string>{kRefinedTrajectoryFile, kSelfCheckFile, kTrajectoriesFile}));
  const Trajectory refined = io::read_tum(work / kRefinedTrajectoryFile);
  const Trajectory map = io::read_tum(mission / "map_poses.tum");
  ASSERT_EQ(refined.size(), map.size());
  for (size_t k = 0; k < map.size(); ++k) ASSERT_EQ(refined[k].t_ns, map[k].t_ns) << k;

  // Against the simulator's truth, computed here from the files.
  const Trajectory truth = io::read_tum(mission / "ground_truth" / "trajectory.tum");
  const double ate_map = ate_rmse(truth, map);
  const double ate_refined = ate_rmse(truth, refined);
  EXPECT_LT(ate_refined, ate_map);

  const auto& report = run.result.report;
  const auto& table = report["evaluation"]["table"];
  const double ate_without =
      table["refined_without_dvl"]["ate"]["translation_m"]["rmse"].get<double>();
  EXPECT_LT(ate_refined, ate_without);
  EXPECT_NEAR(table["map"]["ate"]["translation_m"]["rmse"].get<double>(), ate_map, 1e-9);
  EXPECT_NEAR(table["refined_with_dvl"]["ate"]["translation_m"]["rmse"].get<double>(), ate_refined,
              1e-6);  // the TUM file rounds to 9 significant digits
  EXPECT_TRUE(table["map"]["rpe"].contains("translation_m")) << table["map"]["rpe"].dump();

  // Inputs, solver and calibration figures are there; s_d is 1 in this mission.
  EXPECT_EQ(report["inputs"]["keyframes"]["used"].get<size_t>(), map.size());
  EXPECT_EQ(report["inputs"]["odometry"]["source"], "recorded");
  EXPECT_EQ(report["solver"]["factors"]["dvl"].get<int>(), static_cast<int>(map.size()) - 1);
  EXPECT_GT(report["solver"]["iterations"].get<int>(), 0);
  const auto& scale = report["dvl"]["dvl_scale"];
  EXPECT_EQ(scale["true"].get<double>(), 1.0);
  EXPECT_GT(scale["sigma"].get<double>(), 0.0);
  EXPECT_LT(std::abs(scale["value"].get<double>() - 1.0), 4.0 * scale["sigma"].get<double>());
  EXPECT_EQ(report["dvl"]["gaps"]["gaps_skipped"], 0);
  // The DVL-IMU extrinsic rotation: estimate and 1-sigma per axis, consistent with the truth.
  const auto& rotation = report["dvl"]["dvl_rotation"];
  ASSERT_EQ(rotation["q_body_dvl_xyzw"].size(), 4u);
  ASSERT_EQ(rotation["sigma_deg"].size(), 3u);
  ASSERT_EQ(rotation["error_vs_truth_deg"].size(), 3u);
  for (int a = 0; a < 3; ++a) {
    const double sigma = rotation["sigma_deg"][a].get<double>();
    EXPECT_GT(sigma, 0.0) << a;
    EXPECT_LT(std::abs(rotation["error_vs_truth_deg"][a].get<double>()), 5.0 * sigma + 0.05) << a;
  }

  // The self-check: one CSV row per keyframe whose movement is the refined minus the MAP
  // position, computed here from the two TUM files; the report's RMS is theirs. The bridge's
  // odometry never degenerates, so the MAP has no drift path and its drift is at the floor.
  const auto& check = report["self_check"];
  EXPECT_EQ(check["keyframes"].get<size_t>(), map.size());
  std::ifstream csv(work / kSelfCheckFile);
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.substr(0, 26), "t_s,dx_m,dy_m,dz_m,moved_m");
  double sum_squared = 0.0;
  int flagged = 0;
  for (size_t k = 0; k < map.size(); ++k) {
    ASSERT_TRUE(std::getline(csv, line)) << k;
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 13u) << line;
    const Eigen::Vector3d moved =
        refined[k].T_world_body.translation() - map[k].T_world_body.translation();
    EXPECT_NEAR(v[1], moved.x(), 2e-6) << k;
    EXPECT_NEAR(v[4], moved.norm(), 2e-6) << k;
    EXPECT_EQ(v[9], 0.0) << k;  // drift path
    sum_squared += moved.squaredNorm();
    flagged += static_cast<int>(v[12]);
  }
  EXPECT_FALSE(std::getline(csv, line));
  EXPECT_NEAR(check["translation_m"]["rms"].get<double>(), std::sqrt(sum_squared / map.size()),
              1e-5);
  EXPECT_EQ(check["flagged_keyframes"].get<int>(), flagged);
  EXPECT_TRUE(report["map_noise"]["estimated"].get<bool>());
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(report["map_noise"]["drift_m_per_sqrt_m"]["axes"][a].get<double>(), 0.001, 1e-6);

  // Progress is monotone and ends at 1.
  ASSERT_FALSE(run.progress.empty());
  for (size_t k = 1; k < run.progress.size(); ++k) EXPECT_GE(run.progress[k], run.progress[k - 1]);
  EXPECT_EQ(run.progress.back(), 1.0);
}

// Issue 19: on keel-sim usv-corridor seed 12 (whole path) the refinement ended worse than the
// MAP poses it started from, with DVL (0.196 vs 0.171 m) and without (0.381 m). The MAP walks
// along the corridor (x) where its scan matching degenerates; its drift is now modelled and
// estimated, so neither refinement may end worse than the MAP (without DVL by at most 10 %,
// the target), and the estimated drift must point along the corridor.
TEST_F(RefineStageTest, CorridorRefinementsAreNotWorseThanTheMapPoses) {
  const fs::path mission = temp_root() / "corridor_12";
  testing::simulate(mission, "usv-corridor", 12, 0.0, {"imu", "dvl", "depth"});
  const StageRun run = run_stage(mission, nlohmann::json::object(), temp_root() / "work_corridor");
  const auto& report = run.result.report;
  const auto& table = report["evaluation"]["table"];
  auto ate = [&](const char* row) {
    return table[row]["ate"]["translation_m"]["rmse"].get<double>();
  };
  EXPECT_LT(ate("refined_with_dvl"), ate("map"));
  EXPECT_LT(ate("refined_without_dvl"), 1.10 * ate("map"));
  const auto& drift = report["map_noise"]["drift_m_per_sqrt_m"];
  EXPECT_GT(std::abs(drift["largest_direction"][0].get<double>()), 0.9) << drift.dump();
  EXPECT_GT(drift["principal"][0].get<double>(), 0.02) << drift.dump();
  EXPECT_EQ(report["degenerate_keyframes"]["count"].get<int>(),
            report["solver"]["keyframes"].get<int>() - 1);
}

// keel-sim hauv-hull: the DVL rides the servo tray, which turns up to ~90 deg over the survey.
// Read with its angle-0 extrinsic the velocities pointed wrong (ATE 0.54 m against 0.02 m
// without the DVL); turned back into that frame, the DVL helps again.
TEST_F(RefineStageTest, DvlOnAServoTrayIsTurnedBackIntoItsManifestFrame) {
  const fs::path mission = temp_root() / "hull";
  testing::simulate(mission, "hauv-hull", 2, 0.0, {"imu", "dvl", "depth"});  // whole survey, 236 s
  const StageRun run = run_stage(mission, nlohmann::json::object(), temp_root() / "work_hull");
  const auto& report = run.result.report;
  const auto& tray = report["inputs"]["dvl"]["servo_tray"];
  EXPECT_EQ(tray["servo"], "servo");
  EXPECT_EQ(tray["samples_turned"].get<size_t>(), report["inputs"]["dvl"]["samples"].get<size_t>());
  EXPECT_GT(tray["max_angle_deg"].get<double>(), 45.0);
  const Trajectory truth = io::read_tum(mission / "ground_truth" / "trajectory.tum");
  const double ate_with =
      ate_rmse(truth, io::read_tum(temp_root() / "work_hull" / kRefinedTrajectoryFile));
  const auto& table = report["evaluation"]["table"];
  const double ate_without =
      table["refined_without_dvl"]["ate"]["translation_m"]["rmse"].get<double>();
  EXPECT_LT(ate_with, ate_without);
  EXPECT_LT(ate_with, table["map"]["ate"]["translation_m"]["rmse"].get<double>());
}

TEST_F(RefineStageTest, EstimatesAnInjectedDvlScale) {
  const fs::path mission = simulated_mission("bridge_scale", {"imu", "dvl"}, 1.02);
  const StageRun run =
      run_stage(mission, {{"compare_without_dvl", false}}, temp_root() / "work_scale");
  const auto& scale = run.result.report["dvl"]["dvl_scale"];
  EXPECT_EQ(scale["true"].get<double>(), 1.02);
  EXPECT_LT(std::abs(scale["value"].get<double>() - 1.02), 4.0 * scale["sigma"].get<double>())
      << scale.dump();
  EXPECT_TRUE(run.result.report["evaluation"]["table"]["refined_without_dvl"].is_null());
}

// A mission without recorded lidar odometry: the stage falls back to GICP between keyframe
// scans (worker/slam/gicp_odometry.h). A GICP edge in the wrong frame or direction, or a wrong
// local minimum kept with its (millimetre) point-to-plane confidence, drags the refinement far
// from the truth (before the outlier gate, 1.3 m ATE on this mission without DVL).
TEST_F(RefineStageTest, FallsBackToGicpOdometryWithoutRecordedOdometry) {
  const fs::path dir = temp_root() / "gicp";
  testing::simulate(dir, "usv-bridge", 4, 30.0, {"imu", "dvl", "lidar_h"});
  // Remove trajectories.odometry from mission.yaml (and the file, to be sure it is not read).
  std::ifstream in(dir / "mission.yaml");
  std::string yaml, line;
  while (std::getline(in, line))
    if (line.find("odometry: odometry.tum") == std::string::npos) yaml += line + "\n";
  in.close();
  std::ofstream(dir / "mission.yaml") << yaml;
  fs::remove(dir / "odometry.tum");

  const StageRun run = run_stage(dir, nlohmann::json::object(), temp_root() / "work_gicp");
  const auto& report = run.result.report;
  ASSERT_EQ(report["inputs"]["odometry"]["source"], "gicp") << report["inputs"].dump();
  const Trajectory map = io::read_tum(dir / "map_poses.tum");
  // Keyframes without a scan within the stamp tolerance (the last one here) are dropped.
  const size_t used = report["inputs"]["keyframes"]["used"].get<size_t>();
  EXPECT_GE(used, map.size() - 2);
  EXPECT_EQ(used + report["inputs"]["keyframes"]["dropped_without_scan"].get<size_t>(), map.size());
  // Registrations that failed the outlier gate are left out, not passed on as degenerate edges.
  const auto& odometry = report["inputs"]["odometry"];
  EXPECT_EQ(odometry["edges"].get<size_t>() + odometry["edges_rejected"].get<size_t>(), used - 1);
  EXPECT_GE(odometry["edges"].get<size_t>(), (used - 1) / 2);

  const Trajectory truth = io::read_tum(dir / "ground_truth" / "trajectory.tum");
  const Trajectory refined = io::read_tum(temp_root() / "work_gicp" / kRefinedTrajectoryFile);
  const double ate_map = ate_rmse(truth, map);
  const double ate_refined = ate_rmse(truth, refined);
  EXPECT_LT(ate_refined, 0.8 * ate_map) << "MAP " << ate_map << " m, refined " << ate_refined;
  // Without DVL (IMU, GICP edges, MAP anchors) the refinement must still beat the MAP poses.
  // It did not (0.196 vs 0.050 m) while the gated edges' keyframes were flagged degenerate and
  // their zeroed biases pinned b^a to zero over the mission (0.5 m sag in z).
  const double ate_without_dvl =
      report["evaluation"]["table"]["refined_without_dvl"]["ate"]["translation_m"]["rmse"]
          .get<double>();
  EXPECT_LT(ate_without_dvl, 0.8 * ate_map)
      << "MAP " << ate_map << " m, without DVL " << ate_without_dvl;
  // The GICP edges' disagreement with the MAP increments is reported (it widens their sigmas).
  EXPECT_TRUE(
      report["inputs"]["odometry"]["disagreement_with_map_rms"]["translation_m"].is_array());
}

TEST_F(RefineStageTest, OptionErrorsNameTheOption) {
  const fs::path mission = simulated_mission("bridge", {"imu", "dvl"});
  const std::string unknown = error_of(mission, {{"dvl_scael", 1.0}});
  EXPECT_NE(unknown.find("options.refine.dvl_scael"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("estimate_dvl_scale"), std::string::npos) << unknown;  // the known ones
  const std::string mistyped = error_of(mission, {{"dvl", "yes"}});
  EXPECT_NE(mistyped.find("options.refine.dvl"), std::string::npos) << mistyped;
  EXPECT_NE(mistyped.find("boolean"), std::string::npos) << mistyped;
  const std::string range = error_of(mission, {{"rpe_delta_m", -1.0}});
  EXPECT_NE(range.find("options.refine.rpe_delta_m"), std::string::npos) << range;
  const std::string choice = error_of(mission, {{"odometry", "wheels"}});
  EXPECT_NE(choice.find("options.refine.odometry"), std::string::npos) << choice;
  const std::string sensor = error_of(mission, {{"dvl_sensor", "imu"}});
  EXPECT_NE(sensor.find("options.refine.dvl_sensor"), std::string::npos) << sensor;
}

TEST_F(RefineStageTest, MissionWithoutDvlFailsUnlessDvlIsOff) {
  const fs::path mission = simulated_mission("imu_only", {"imu"});
  const std::string error = error_of(mission, nlohmann::json::object());
  EXPECT_NE(error.find("no sensor of type dvl"), std::string::npos) << error;
  EXPECT_NE(error.find("refine.dvl=false"), std::string::npos) << error;

  const fs::path work = temp_root() / "work_imu_only";
  // Loop closures off keeps the MAP anchors: one per keyframe.
  const StageRun run = run_stage(mission, {{"dvl", false}, {"loop_closures", false}}, work);
  const Trajectory refined = io::read_tum(work / kRefinedTrajectoryFile);
  EXPECT_EQ(refined.size(), io::read_tum(mission / "map_poses.tum").size());
  EXPECT_EQ(run.result.report["solver"]["factors"]["map_anchors"].get<size_t>(), refined.size());
  EXPECT_EQ(run.result.report["solver"]["factors"]["loop_closures"], 0);
  EXPECT_TRUE(run.result.report["dvl"].is_null());
  EXPECT_TRUE(run.result.report["evaluation"]["table"]["refined_with_dvl"].is_null());
  EXPECT_EQ(run.result.report["solver"]["factors"]["dvl"], 0);
}

TEST_F(RefineStageTest, CancelStopsTheStage) {
  const fs::path mission = simulated_mission("bridge", {"imu", "dvl"});
  StageContext context;
  context.mission_dir = mission;
  context.work_dir = temp_root() / "work_cancel";
  fs::create_directories(context.work_dir);
  context.canceled = [] { return true; };
  EXPECT_THROW(make_refine_stage()->run(context), Canceled);
  EXPECT_FALSE(fs::exists(context.work_dir / kRefinedTrajectoryFile));
}

}  // namespace
}  // namespace keel::pipeline
