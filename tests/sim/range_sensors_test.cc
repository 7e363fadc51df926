#include "tests/sim/range_sensors.h"

#include <gtest/gtest.h>

#include "tests/sim/mesh_bvh.h"
#include "tests/sim/scenarios.h"

namespace keel::sim {
namespace {

struct Sweep {
  PointCloud cloud;
  Pose3 T_body_sensor;
};

// Points back in world with the true pose at each point's firing time.
std::vector<Eigen::Vector3d> to_world(const PointCloud& cloud, const PoseTable& poses,
                                      const Pose3& T_body_sensor, double t_start) {
  std::vector<Eigen::Vector3d> out;
  for (size_t i = 0; i < cloud.size(); ++i)
    out.push_back(poses.T_world_body(t_start + cloud.time_s[i]) * T_body_sensor *
                  cloud.xyz[i].cast<double>());
  return out;
}

TEST(Lidar, PointsLieOnTheAnalyticSceneAndSpanOneSweep) {
  for (const char* name : {"usv-bridge", "usv-corridor"}) {
    const Scenario s = make_scenario(name, 11);
    const PoseTable poses(*s.motion, 40.0);
    SpinningLidarOptions options;
    for (const char* lidar : {"lidar_h", "lidar_v"}) {
      Rng rng(11, Stream::kLidarH, 0);
      const double t_start = 30.0;
      const Pose3 T = s.T_body_sensor.at(lidar);
      const PointCloud cloud = simulate_lidar_sweep(*s.world, poses, T, t_start, options, rng);
      ASSERT_GT(cloud.size(), 1000u) << name << " " << lidar;
      ASSERT_EQ(cloud.time_s.size(), cloud.size());
      ASSERT_EQ(cloud.ring.size(), cloud.size());
      const auto world = to_world(cloud, poses, T, t_start);
      size_t close = 0;
      float t_min = 1.0f, t_max = -1.0f;
      for (size_t i = 0; i < world.size(); ++i) {
        close += s.analytic->distance_to_returning_surface(world[i]) < 4.0 * options.range_sigma_m;
        t_min = std::min(t_min, cloud.time_s[i]);
        t_max = std::max(t_max, cloud.time_s[i]);
        EXPECT_LT(cloud.ring[i], 16);
        // The firing time follows the azimuth: one revolution per 100 ms sweep.
        double azimuth = std::atan2(cloud.xyz[i].y(), cloud.xyz[i].x());
        if (azimuth < -1e-4) azimuth += 2.0 * M_PI;
        EXPECT_NEAR(cloud.time_s[i], azimuth / (2.0 * M_PI) * 0.1, 1e-5);
      }
      EXPECT_GE(double(close) / world.size(), 0.99) << name << " " << lidar;
      EXPECT_GE(t_min, 0.0f);
      EXPECT_LT(t_max, 0.1f);
      // The horizontal lidar sees walls all around: its points cover the whole sweep.
      if (std::string(lidar) == "lidar_h") {
        EXPECT_GT(t_max, 0.099f);
      }
    }
  }
}

// Without deskew (all points with the sweep-start pose) the last points of a sweep are off by
// the vehicle's motion during the sweep (~1.2 m/s * 0.1 s), the first ones are not.
TEST(Lidar, DeskewHasWorkToDo) {
  const Scenario s = make_scenario("usv-bridge", 12);
  const PoseTable poses(*s.motion, 60.0);
  Rng rng(12, Stream::kLidarH, 1);
  const double t_start = 50.0;
  const Pose3 T = s.T_body_sensor.at("lidar_h");
  const PointCloud cloud = simulate_lidar_sweep(*s.world, poses, T, t_start, {}, rng);
  const Pose3 T_start = poses.T_world_body(t_start) * T;
  double early = 0, late = 0;
  int n_early = 0, n_late = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.xyz[i].cast<double>();
    const double shift =
        (T_start * p - poses.T_world_body(t_start + cloud.time_s[i]) * T * p).norm();
    if (cloud.time_s[i] < 0.005) early += shift, ++n_early;
    if (cloud.time_s[i] > 0.095) late += shift, ++n_late;
  }
  ASSERT_GT(n_early, 10);
  ASSERT_GT(n_late, 10);
  EXPECT_LT(early / n_early, 0.02);
  EXPECT_GT(late / n_late, 0.1);
}

TEST(Sonar, PointsAreUnderwaterOnTheScene) {
  const Scenario s = make_scenario("usv-bridge", 13);
  const PoseTable poses(*s.motion, 30.0);
  ProfilingSonarOptions options;
  size_t total = 0, close = 0;
  for (double t = 5.0; t < 30.0; t += 2.5) {
    Rng rng(13, Stream::kSonar, static_cast<uint64_t>(t * 10));
    const Pose3 T_world_sonar = poses.T_world_body(t) * s.T_body_sensor.at("sonar");
    const PointCloud cloud = simulate_sonar_ping(*s.world, T_world_sonar, options, rng);
    for (const auto& p : cloud.xyz) {
      const Eigen::Vector3d w = T_world_sonar * p.cast<double>();
      EXPECT_LT(w.z(), 0.0);
      close += s.analytic->distance_to_returning_surface(w) < 4.0 * options.range_sigma_m;
      ++total;
    }
  }
  ASSERT_GT(total, 500u);
  EXPECT_GE(double(close) / total, 0.99);
}

// The BVH agrees with a brute-force cast over every triangle.
TEST(MeshBvh, MatchesBruteForce) {
  const TriangleMesh mesh = make_hull_mesh({});
  const MeshBvh bvh(mesh);
  Rng rng(5, Stream::kScene);
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d origin(rng.uniform(-25, 25), rng.uniform(-10, 10), rng.uniform(-8, 3));
    const Eigen::Vector3d dir =
        Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()).normalized();
    MeshHit a, b;
    const bool ha = bvh.raycast(origin, dir, 0.0, 100.0, &a);
    const bool hb = raycast_brute_force(mesh, origin, dir, 0.0, 100.0, &b);
    ASSERT_EQ(ha, hb) << i;
    if (ha) {
      EXPECT_NEAR(a.t, b.t, 1e-9);
      ++hits;
    }
  }
  EXPECT_GT(hits, 100);
}

}  // namespace
}  // namespace keel::sim
