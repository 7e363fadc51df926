// The streaming MapBuilder: batches of N_I scans (the last partial one included), stage
// filters, streaming voxel map equal to a batch voxel grid, scans outside the trajectory.
#include <gtest/gtest.h>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/map_builder.h"
#include "worker/mapping/slam_map.h"
#include "worker/mapping/stamped_transforms.h"
#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {
namespace {

using testing::random_cloud;
using testing::sample_trajectory;

TransformTree make_tree() {
  TransformTree tree(sample_trajectory(0.0, 30.0, 0.01, {1.0, 0.5, 0.0}, 0.05));
  tree.set_extrinsic("lidar",
                     make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ())),
                               Eigen::Vector3d(0.1, 0.2, 0.3)));
  tree.set_extrinsic("sonar", Pose3::Identity());
  return tree;
}

MapBuilderOptions no_filters(int scans_per_intermediary) {
  MapBuilderOptions options;
  options.scans_per_intermediary = scans_per_intermediary;
  options.default_sensor.scan_filters = FilterChain{};
  return options;
}

TEST(MapBuilder, LastPartialIntermediaryBatchIsIncluded) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(10);
  // A crop box that keeps everything, so the intermediary stage runs and counts.
  options.default_sensor.intermediary_filters.filters.push_back(
      CropBoxFilter{Eigen::Vector3d::Constant(-1e4), Eigen::Vector3d::Constant(1e4), false});
  MapBuilder builder(tree, options);
  for (int s = 0; s < 25; ++s) {
    PointCloud scan = random_cloud(100, -5.0f, 5.0f, static_cast<unsigned>(s));
    scan.t_ns = seconds_to_ns(1.0 + 0.1 * s);
    builder.add_scan("lidar", scan);
  }
  builder.finish();
  const SensorMapStats& stats = builder.stats("lidar");
  EXPECT_EQ(stats.intermediary_maps, 3u);  // 10 + 10 + 5
  EXPECT_EQ(stats.intermediary_stage.applications, 3u);
  ASSERT_EQ(stats.intermediary_stage.steps.size(), 1u);
  EXPECT_EQ(stats.intermediary_stage.steps[0].points_in, 2500u);
  EXPECT_EQ(builder.sensor_map("lidar").size(), 2500u);
  EXPECT_EQ(stats.points_out, 2500u);
}

TEST(MapBuilder, PointsLandWhereTheTreeSaysInScanOrder) {
  const TransformTree tree = make_tree();
  MapBuilder builder(tree, no_filters(4));
  std::vector<Eigen::Vector3d> expected;
  for (int s = 0; s < 7; ++s) {
    PointCloud scan = random_cloud(50, -20.0f, 20.0f, 100 + s);
    scan.t_ns = seconds_to_ns(2.0 + 0.37 * s);
    scan.time_s.assign(scan.size(), 0.0f);  // deskew with all-zero offsets is the identity
    const Pose3 T_world_lidar = tree.T_world_sensor("lidar", scan.t_ns);
    for (const auto& p : scan.xyz) expected.push_back(T_world_lidar * p.cast<double>());
    builder.add_scan("lidar", scan);
  }
  builder.finish();
  const PointCloud& map = builder.sensor_map("lidar");
  ASSERT_EQ(map.size(), expected.size());
  for (size_t k = 0; k < map.size(); ++k) {
    ASSERT_LT((map.xyz[k].cast<double>() - expected[k]).norm(), 1e-4) << k;
  }
  EXPECT_EQ(map.frame, "world");
  EXPECT_TRUE(map.time_s.empty());  // per-scan offsets do not survive into the world map
  EXPECT_EQ(map.intensity.size(), map.size());
}

TEST(MapBuilder, StreamingFinalVoxelGridEqualsOneVoxelGridOverTheWholeMap) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(3);
  options.default_sensor.final_filters.filters.push_back(VoxelGridFilter{0.5});
  options.default_sensor.final_filters.filters.push_back(RadiusOutlierFilter{1.0, 2});
  MapBuilder builder(tree, options);
  MapBuilder reference_builder(tree, no_filters(3));
  for (int s = 0; s < 11; ++s) {
    PointCloud scan = random_cloud(400, -4.0f, 4.0f, 200 + s);
    scan.t_ns = seconds_to_ns(5.0 + 0.1 * s);
    builder.add_scan("sonar", scan);
    reference_builder.add_scan("sonar", scan);
  }
  builder.finish();
  reference_builder.finish();
  PointCloud expected = reference_builder.sensor_map("sonar");
  apply_voxel_grid(VoxelGridFilter{0.5}, expected);
  apply_radius_outlier(RadiusOutlierFilter{1.0, 2}, expected);
  const PointCloud& map = builder.sensor_map("sonar");
  ASSERT_EQ(map.size(), expected.size());
  for (size_t k = 0; k < map.size(); ++k) {
    ASSERT_LT((map.xyz[k] - expected.xyz[k]).norm(), 1e-5f) << k;
  }
  const SensorMapStats& stats = builder.stats("sonar");
  ASSERT_EQ(stats.final_stage.steps.size(), 2u);
  EXPECT_EQ(stats.final_stage.steps[0].filter, "voxel_grid");
  EXPECT_EQ(stats.final_stage.steps[0].points_in, 4400u);
  EXPECT_EQ(stats.final_stage.steps[1].points_out, map.size());
}

TEST(MapBuilder, MergeRadiusReachesTheStreamedVoxelGridInScanOrder) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(3);
  options.final_voxel_merge_radius_leaves = 1.0;
  options.default_sensor.final_filters.filters.push_back(VoxelGridFilter{0.5});
  MapBuilder builder(tree, options);
  MapBuilder reference_builder(tree, no_filters(3));  // every point, in W, in scan order
  for (int s = 0; s < 11; ++s) {
    PointCloud scan = random_cloud(400, -4.0f, 4.0f, 300 + s);
    scan.t_ns = seconds_to_ns(5.0 + 0.1 * s);
    builder.add_scan("sonar", scan);
    reference_builder.add_scan("sonar", scan);
  }
  builder.finish();
  reference_builder.finish();
  VoxelAccumulator expected(0.5, 0.5);  // the merge rule over the points in the same order
  expected.add(reference_builder.sensor_map("sonar"));
  const PointCloud expected_map = expected.centroids();
  ASSERT_GT(expected.points_merged(), 0u);
  const PointCloud& map = builder.sensor_map("sonar");
  ASSERT_EQ(map.size(), expected_map.size());
  for (size_t k = 0; k < map.size(); ++k) {
    ASSERT_LT((map.xyz[k] - expected_map.xyz[k]).norm(), 1e-5f) << k;
  }
  options.final_voxel_merge_radius_leaves = 2.5;  // beyond the 5x5x5 neighbourhood
  EXPECT_THROW(MapBuilder(tree, options), std::invalid_argument);
}

// add_scans on two threads against add_scan scan by scan: two sensors interleaved, a DROR
// scan filter, a ROR intermediary filter, a streaming final voxel grid and scans outside the
// trajectory; the maps must be identical point for point (commits follow feed order).
TEST(MapBuilder, ParallelFeedEqualsScanByScan) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(3);
  options.default_sensor.scan_filters.filters.push_back(DrorFilter{3.0, 2.0, 3, 0.3});
  options.default_sensor.intermediary_filters.filters.push_back(RadiusOutlierFilter{1.0, 2});
  options.default_sensor.final_filters.filters.push_back(VoxelGridFilter{0.4});
  std::vector<std::pair<std::string, PointCloud>> scans;
  for (int s = 0; s < 40; ++s) {
    // Uneven scans, so later scans are often ready before earlier ones and wait their turn.
    PointCloud scan = random_cloud(s % 4 == 0 ? 3000 : 100, -4.0f, 4.0f, 700 + s);
    scan.t_ns = seconds_to_ns(s == 17 ? 99.0 : 3.0 + 0.1 * s);  // 99 s: outside the poses
    scans.emplace_back(s % 3 == 0 ? "sonar" : "lidar", scan);
  }
  options.threads = 1;
  MapBuilder serial(tree, options);
  for (const auto& [sensor, scan] : scans) serial.add_scan(sensor, scan);
  serial.finish();
  for (const int threads : {2, 5}) {
    options.threads = threads;
    MapBuilder parallel(tree, options);
    size_t next = 0;
    parallel.add_scans([&](std::string& sensor, PointCloud& scan) {
      if (next == scans.size()) return false;
      sensor = scans[next].first;
      scan = scans[next].second;
      ++next;
      return true;
    });
    parallel.finish();
    for (const std::string sensor : {"lidar", "sonar"}) {
      SCOPED_TRACE(sensor + " on " + std::to_string(threads) + " threads");
      const PointCloud& a = serial.sensor_map(sensor);
      const PointCloud& b = parallel.sensor_map(sensor);
      ASSERT_GT(a.size(), 0u);
      ASSERT_EQ(a.size(), b.size());
      for (size_t k = 0; k < a.size(); ++k) ASSERT_EQ(a.xyz[k], b.xyz[k]) << k;
      EXPECT_EQ(serial.stats(sensor).scans, parallel.stats(sensor).scans);
      EXPECT_EQ(serial.stats(sensor).scans_outside_trajectory,
                parallel.stats(sensor).scans_outside_trajectory);
      EXPECT_EQ(serial.stats(sensor).intermediary_maps, parallel.stats(sensor).intermediary_maps);
    }
  }
  EXPECT_EQ(serial.stats("lidar").scans_outside_trajectory +
                serial.stats("sonar").scans_outside_trajectory,
            1u);
}

TEST(MapBuilder, ParallelFeedRethrowsTheFirstError) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(2);
  options.threads = 2;
  {
    MapBuilder builder(tree, options);
    int fed = 0;
    EXPECT_THROW(builder.add_scans([&](std::string& sensor, PointCloud& scan) {
      if (fed == 5) throw std::runtime_error("feed failed");
      sensor = "lidar";
      scan = random_cloud(50, -2.0f, 2.0f, fed);
      scan.t_ns = seconds_to_ns(4.0 + 0.1 * fed++);
      return true;
    }),
                 std::runtime_error);
  }
  {
    // A scan-level error (point times that do not match the points) stops the feed too.
    MapBuilder builder(tree, options);
    int fed = 0;
    EXPECT_THROW(builder.add_scans([&](std::string& sensor, PointCloud& scan) {
      if (fed == 1000) return false;
      sensor = "lidar";
      scan = random_cloud(50, -2.0f, 2.0f, fed);
      scan.t_ns = seconds_to_ns(4.0 + 0.001 * fed);
      if (fed++ == 3) scan.time_s.assign(7, 0.0f);
      return true;
    }),
                 std::invalid_argument);
    EXPECT_LT(fed, 1000);
  }
}

TEST(MapBuilder, ScanFiltersRunInTheSensorFrame) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(5);
  // Remove the vessel: everything within 2 m of the SENSOR, wherever the sensor is in W.
  options.default_sensor.scan_filters.filters.push_back(
      CropBoxFilter{Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2), true});
  MapBuilder builder(tree, options);
  PointCloud scan = random_cloud(2000, -4.0f, 4.0f, 300);
  scan.t_ns = seconds_to_ns(20.0);  // the body is ~20 m from the origin of W by then
  size_t outside_vessel = 0;
  for (const auto& p : scan.xyz) outside_vessel += (p.array().abs() > 2.0f).any();
  builder.add_scan("lidar", scan);
  builder.finish();
  EXPECT_EQ(builder.sensor_map("lidar").size(), outside_vessel);
}

TEST(MapBuilder, ScansOutsideTheTrajectoryAreSkippedAndCountedOrRefused) {
  const TransformTree tree = make_tree();
  MapBuilder builder(tree, no_filters(10));
  PointCloud early = random_cloud(10, -1.0f, 1.0f, 1);
  early.t_ns = seconds_to_ns(-1.0);
  builder.add_scan("lidar", early);
  PointCloud fine = random_cloud(10, -1.0f, 1.0f, 2);
  fine.t_ns = seconds_to_ns(1.0);
  fine.xyz[3] = Eigen::Vector3f(std::nanf(""), 0.0f, 0.0f);
  builder.add_scan("lidar", fine);
  builder.finish();
  EXPECT_EQ(builder.stats("lidar").scans, 2u);
  EXPECT_EQ(builder.stats("lidar").scans_outside_trajectory, 1u);
  EXPECT_EQ(builder.stats("lidar").non_finite_points, 1u);
  EXPECT_EQ(builder.sensor_map("lidar").size(), 9u);

  MapBuilderOptions strict = no_filters(10);
  strict.skip_scans_outside_trajectory = false;
  MapBuilder strict_builder(tree, strict);
  EXPECT_THROW(strict_builder.add_scan("lidar", early), std::out_of_range);
  EXPECT_THROW(strict_builder.add_scan("camera", fine), std::invalid_argument);
}

TEST(MapBuilder, DrorOnlyAsAScanFilter) {
  const TransformTree tree = make_tree();
  MapBuilderOptions options = no_filters(10);
  options.sensors["sonar"].intermediary_filters.filters.push_back(DrorFilter{});
  EXPECT_THROW(MapBuilder(tree, options), std::invalid_argument);
  options.sensors["sonar"].intermediary_filters = FilterChain{};
  options.scans_per_intermediary = 0;
  EXPECT_THROW(MapBuilder(tree, options), std::invalid_argument);
}

TEST(MapBuilder, CombinedMapIsTheUnionOfSensorMaps) {
  const TransformTree tree = make_tree();
  MapBuilder builder(tree, no_filters(2));
  for (int s = 0; s < 5; ++s) {
    PointCloud scan = random_cloud(30, -3.0f, 3.0f, 400 + s);
    scan.t_ns = seconds_to_ns(3.0 + 0.2 * s);
    builder.add_scan(s % 2 ? "sonar" : "lidar", scan);
  }
  builder.finish();
  EXPECT_EQ(builder.combined_map().size(), 150u);
  EXPECT_EQ(builder.sensors(), (std::vector<std::string>{"lidar", "sonar"}));
}

TEST(MapBuilder, SensorOptionsFromJson) {
  const SensorMapOptions sonar = sensor_map_options_from_json(
      nlohmann::json::parse(R"({"intermediary_filters": [{"type": "ror", "radius": 0.2,
                                "min_neighbors": 3}], "deskew": false})"),
      "map.sensors.sonar", SensorMapOptions{table_iv_sonar_scan_filters(), {}, {}, true});
  EXPECT_FALSE(sonar.deskew);
  EXPECT_EQ(filter_chain_to_json(sonar.scan_filters),
            filter_chain_to_json(table_iv_sonar_scan_filters()));  // kept from the defaults
  ASSERT_EQ(sonar.intermediary_filters.filters.size(), 1u);
  EXPECT_EQ(to_json(sonar)["intermediary_filters"][0]["radius"], 0.2);
  try {
    sensor_map_options_from_json(nlohmann::json::parse(R"({"final_filter": []})"), "map.x");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("map.x.final_filter: unknown key"), std::string::npos);
  }
  EXPECT_THROW(sensor_map_options_from_json(nlohmann::json::parse(R"({"deskew": 1})"), "m"),
               std::invalid_argument);
}

TEST(SlamMap, UsesTheScanNearestEachKeyframeVoxelized) {
  // Keyframes every 1 s; scans every 0.1 s, each a single tight cluster of 20 points.
  Trajectory keyframes = sample_trajectory(1.0, 5.0, 1.0, {1.0, 0.0, 0.0}, 0.0);
  SlamMapOptions options;
  options.keyframe_leaf_m = 0.2;
  options.match_tolerance_s = 0.05;
  SlamMapBuilder builder(keyframes, Pose3::Identity(), options);
  for (int s = 0; s <= 60; ++s) {
    PointCloud scan;
    scan.t_ns = seconds_to_ns(0.02 + 0.1 * s);  // 20 ms off the keyframes
    for (int m = 0; m < 20; ++m) scan.xyz.emplace_back(10.05f + 0.001f * m, 0.05f, 0.05f);
    scan.intensity.assign(20, static_cast<float>(s));
    builder.add_scan(scan);
  }
  const PointCloud map = builder.finish();
  EXPECT_EQ(builder.keyframes_used(), 5u);
  ASSERT_EQ(map.size(), 5u);  // one voxel per keyframe scan
  for (size_t k = 0; k < map.size(); ++k) {
    // Keyframe k at t = k + 1 s sits at x = k + 1; its scan is the one 20 ms later.
    EXPECT_NEAR(map.xyz[k].x(), 10.0595 + (k + 1.0), 1e-4);
    EXPECT_EQ(map.intensity[k], 10.0f * (k + 1));
  }
}

}  // namespace
}  // namespace keel::mapping
