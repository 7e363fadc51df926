#include "worker/pipeline/ingest_stage.h"

#include <gtest/gtest.h>

#include "io_test_util.h"
#include "test_bundle.h"

namespace keel::pipeline {
namespace {

using io::testing::TempDir;

TEST(IngestStage, ReportsCountsRatesGapsPointsAndPaths) {
  TempDir dir;
  const auto figures = io::testing::write_bundle(dir.path(), /*imu_gap=*/true);
  StageContext context;
  context.mission_dir = dir.path();
  context.work_dir = dir.path();
  std::vector<double> progress;
  context.progress = [&](double p) { progress.push_back(p); };
  auto stage = make_ingest_stage();
  EXPECT_EQ(stage->name(), "ingest");
  const StageResult result = stage->run(context);
  const auto& r = result.report;
  EXPECT_TRUE(result.artifacts.empty());
  EXPECT_EQ(r["mission"]["name"], "test-bundle");

  const auto& imu = r["sensors"]["imu"];
  EXPECT_EQ(imu["type"], "imu");
  EXPECT_EQ(imu["count"], figures.imu_samples - figures.imu_dropped);
  EXPECT_DOUBLE_EQ(imu["duration_s"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(imu["rate_hz_measured"].get<double>(), 350.0 / 2.0);
  EXPECT_EQ(imu["gaps"]["count"], 1);
  EXPECT_NEAR(imu["gaps"]["longest_interval_s"].get<double>(), 51 * 0.005, 1e-12);
  EXPECT_EQ(imu["extrinsic"], "mission.yaml");

  const auto& dvl = r["sensors"]["dvl"];
  EXPECT_EQ(dvl["count"], figures.dvl_samples);
  EXPECT_NEAR(dvl["rate_hz_measured"].get<double>(), 20.0, 1e-9);
  EXPECT_EQ(dvl["gaps"]["count"], 0);

  const auto& lidar = r["sensors"]["lidar_h"];
  EXPECT_EQ(lidar["count"], figures.scans);
  EXPECT_EQ(lidar["points"]["total"], 100 + 110 + 120 + 130 + 140);
  EXPECT_EQ(lidar["points"]["per_scan"]["min"], 100.0);
  EXPECT_EQ(lidar["points"]["per_scan"]["mean"], 120.0);
  EXPECT_EQ(lidar["points"]["per_scan"]["max"], 140.0);
  EXPECT_NEAR(lidar["time_field"]["span_s"]["max"].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(lidar["time_field"]["offset_min_s"].get<double>(), 0.0, 1e-9);

  const auto& cam = r["sensors"]["cam0"];
  EXPECT_EQ(cam["count"], figures.images);
  EXPECT_EQ(cam["formats"][0], nlohmann::json({8, 6, 1, 8}));

  const auto& odometry = r["trajectories"]["odometry"];
  EXPECT_EQ(odometry["count"], figures.odometry_poses);
  EXPECT_NEAR(odometry["path_length_m"].get<double>(), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(odometry["duration_s"].get<double>(), 2.0);
  EXPECT_EQ(r["trajectories"]["map"]["count"], 3);

  bool gap_warned = false;
  for (const auto& w : r["warnings"])
    gap_warned = gap_warned || w.get<std::string>().find("imu: 1 gaps") == 0;
  EXPECT_TRUE(gap_warned) << r["warnings"].dump();
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back(), 1.0);
  for (size_t i = 1; i < progress.size(); ++i) EXPECT_GE(progress[i], progress[i - 1]);
}

TEST(IngestStage, BadBundleFailsNamingTheFileAndCancelStops) {
  TempDir dir;
  io::testing::write_bundle(dir.path());
  io::testing::write_text(dir / "dvl.csv", "t,vx,vy,vz\n1.0,0,0,0\n0.5,0,0,0\n");
  StageContext context;
  context.mission_dir = dir.path();
  io::testing::expect_error([&] { make_ingest_stage()->run(context); },
                            {"dvl.csv:3:", "decreasing"});

  io::testing::write_bundle(dir.path());
  context.canceled = [] { return true; };
  EXPECT_THROW(make_ingest_stage()->run(context), Canceled);
  context.canceled = [] { return false; };
  context.options = {{"gap_factr", 3}};
  io::testing::expect_error(
      [&] { make_ingest_stage()->run(context); },
      {"options.ingest.gap_factr: unknown option (known: gap_factor, rate_tolerance)"});
}

TEST(IngestStage, ImageSizeDifferentFromTheCameraModelIsAnError) {
  TempDir dir;
  io::testing::write_bundle(dir.path());
  io::ImageFrame image{0, 9, 6, 1, 8, std::vector<uint8_t>(54, 0)};
  io::write_png(dir / "cam0" / "img_1.png", image);
  StageContext context;
  context.mission_dir = dir.path();
  io::testing::expect_error([&] { make_ingest_stage()->run(context); },
                            {"img_1.png", "9x6", "8x6"});
}

}  // namespace
}  // namespace keel::pipeline
