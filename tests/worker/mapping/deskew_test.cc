// Motion compensation: a straight wall scanned while moving and turning comes out straight.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <random>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/deskew.h"

namespace keel::mapping {
namespace {

using testing::sample_trajectory;

const Eigen::Vector3d kVelocity(1.5, 2.0, 0.1);  // m/s
constexpr double kYawRate = 0.8;                 // rad/s
constexpr double kWallX = 12.0;                  // the wall is the plane x = 12 in W
constexpr double kNoiseM = 0.002;

Pose3 body_to_lidar() {
  return make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX())),
                   Eigen::Vector3d(0.3, -0.1, 0.4));
}

// One 0.1 s sweep: rays fired at increasing times, each from the sensor pose at its own time.
PointCloud simulate_sweep(const TransformTree& tree, TimeNs t_scan_ns, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  PointCloud scan;
  scan.t_ns = t_scan_ns;
  scan.frame = "lidar";
  const int firings = 2000;
  for (int k = 0; k < firings; ++k) {
    const double dt = 0.1 * k / firings;
    const Pose3 T_world_lidar = tree.T_world_sensor("lidar", t_scan_ns + std::llround(dt * 1e9));
    for (int ring = 0; ring < 8; ++ring) {
      const double azimuth = -0.7 + 1.4 * k / firings;  // sweeps across the wall
      const double elevation = -0.25 + 0.07 * ring;
      const Eigen::Vector3d dir_lidar(std::cos(elevation) * std::cos(azimuth),
                                      std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const Eigen::Vector3d origin = T_world_lidar.translation();
      const Eigen::Vector3d dir_world = T_world_lidar.linear() * dir_lidar;
      if (dir_world.x() <= 0.1) continue;
      const double range = (kWallX - origin.x()) / dir_world.x() + noise(rng);
      scan.xyz.push_back((range * dir_lidar).cast<float>());
      scan.time_s.push_back(static_cast<float>(dt));
      scan.ring.push_back(static_cast<uint16_t>(ring));
    }
  }
  return scan;
}

// RMS distance of the points to their least-squares plane.
double plane_fit_rms(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) covariance += (p - mean) * (p - mean).transpose();
  covariance /= static_cast<double>(points.size());
  return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues()[0]);
}

std::vector<Eigen::Vector3d> to_world(const PointCloud& scan, const Pose3& T_world_lidar) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : scan.xyz) out.push_back(T_world_lidar * p.cast<double>());
  return out;
}

TransformTree make_tree() {
  // 200 Hz poses of constant-rate motion: interpolation is exact, so the only error left after
  // deskewing is the range noise.
  TransformTree tree(sample_trajectory(0.0, 10.0, 0.005, kVelocity, kYawRate));
  tree.set_extrinsic("lidar", body_to_lidar());
  return tree;
}

TEST(Deskew, RestoresAStraightWall) {
  const TransformTree tree = make_tree();
  const TimeNs t_scan = seconds_to_ns(0.2);  // heading ~0.16 rad: facing the wall
  const PointCloud raw = simulate_sweep(tree, t_scan, 7);
  ASSERT_GT(raw.size(), 10000u);
  const Pose3 T_world_lidar = tree.T_world_sensor("lidar", t_scan);

  const double skewed_rms = plane_fit_rms(to_world(raw, T_world_lidar));
  PointCloud deskewed = raw;
  const Pose3 returned = deskew_scan(tree, "lidar", deskewed);
  EXPECT_TRUE(returned.isApprox(T_world_lidar, 1e-12));
  const std::vector<Eigen::Vector3d> world = to_world(deskewed, T_world_lidar);
  const double deskewed_rms = plane_fit_rms(world);

  EXPECT_GT(skewed_rms, 0.05) << "the uncompensated wall should be bent";
  EXPECT_LT(deskewed_rms, 1.5 * kNoiseM) << "noise is " << kNoiseM;
  // And it is the right wall: x = 12 in W (float storage of 12 m ranges costs ~1 um).
  double mean_abs_offset = 0.0;
  for (const auto& p : world) mean_abs_offset += std::abs(p.x() - kWallX);
  EXPECT_LT(mean_abs_offset / world.size(), 1.5 * kNoiseM);
}

// The largest distance between deskew_scan's points and a per-point TF lookup, on a trajectory
// with stamps at irregular intervals (min_step_s..max_step_s) turning at up to rate_rad_s.
double worst_against_per_point_lookup(double min_step_s, double max_step_s, double rate_rad_s) {
  Trajectory poses;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> step(min_step_s, max_step_s);
  for (double t = 0.0; t < 2.0; t += step(rng)) {
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(rate_rad_s / 3.0 * std::sin(3 * t), Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(0.3 * rate_rad_s * t * t, Eigen::Vector3d::UnitY()));
    poses.push_back({std::llround(t * 1e9), make_pose(q, Eigen::Vector3d(t * t, std::cos(t), t))});
  }
  TransformTree tree(poses);
  tree.set_extrinsic("lidar", body_to_lidar());
  PointCloud scan = testing::random_cloud(5000, -20.0f, 20.0f, 11);
  scan.t_ns = seconds_to_ns(1.0);
  std::uniform_real_distribution<float> offset(-0.05f, 0.1f);  // unsorted, some negative
  for (size_t k = 0; k < scan.size(); ++k) scan.time_s.push_back(offset(rng));
  const PointCloud raw = scan;
  deskew_scan(tree, "lidar", scan);

  const Pose3 T_ref_inverse = tree.T_world_sensor("lidar", raw.t_ns).inverse();
  double worst = 0.0;
  for (size_t k = 0; k < raw.size(); ++k) {
    const TimeNs t_point = raw.t_ns + std::llround(static_cast<double>(raw.time_s[k]) * 1e9);
    const Eigen::Vector3d expected =
        T_ref_inverse * tree.T_world_sensor("lidar", t_point) * raw.xyz[k].cast<double>();
    worst = std::max(worst, (expected - scan.xyz[k].cast<double>()).norm());
  }
  return worst;
}

TEST(Deskew, EqualsAPerPointLookupOnAnIrregularTrajectory) {
  // Stamps 2-20 ms apart at up to ~1 rad/s: every knot segment turns by well under 0.2 rad.
  EXPECT_LT(worst_against_per_point_lookup(0.002, 0.02, 1.0), 1e-5);  // float storage, ~30 m
  // Stamps 20-60 ms apart at up to ~40 rad/s: segments turn by up to ~2 rad, past the small
  // angle series of the segment slerp.
  EXPECT_LT(worst_against_per_point_lookup(0.02, 0.06, 40.0), 1e-5);
}

TEST(Deskew, RefusesSweepsInTheWrongUnitsAndTimesOutsideTheTrajectory) {
  const TransformTree tree = make_tree();
  PointCloud scan = testing::random_cloud(100, -5.0f, 5.0f, 1);
  scan.t_ns = seconds_to_ns(5.0);
  // Ouster stamps points in nanoseconds; read as seconds they span "50 million seconds".
  for (size_t k = 0; k < scan.size(); ++k) scan.time_s.push_back(1e6f * k);
  try {
    deskew_scan(tree, "lidar", scan);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nanoseconds read as seconds"), std::string::npos);
  }
  for (size_t k = 0; k < scan.size(); ++k) scan.time_s[k] = 0.001f * k;
  scan.t_ns = seconds_to_ns(9.95);  // the sweep runs past the trajectory's end (10 s)
  EXPECT_THROW(deskew_scan(tree, "lidar", scan), std::out_of_range);
  scan.time_s[3] = std::nanf("");
  scan.t_ns = seconds_to_ns(5.0);
  EXPECT_THROW(deskew_scan(tree, "lidar", scan), std::invalid_argument);
}

}  // namespace
}  // namespace keel::mapping
