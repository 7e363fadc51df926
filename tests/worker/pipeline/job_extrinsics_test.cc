// A job's extrinsic overrides (docs/calibration.md, section 1): load_job_mission writes them
// into the mission every stage reads, a relative T_<reference>_<sensor> composes with the
// reference's extrinsic, errors name the option path and the sensor, and a map built with an
// override is the map without it moved by the closed-form transform the override implies.
#include "worker/pipeline/job_extrinsics.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "tests/error_of.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/pipeline/job_runner.h"
#include "worker/stages/map/artifacts.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kDeg = M_PI / 180.0;

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_job_extrinsics_" + std::to_string(::getpid()));
}

Pose3 pose(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_deg) {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(rpy_deg.z() * kDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy_deg.y() * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy_deg.x() * kDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = xyz_m;
  return T;
}

json pose_json(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_deg) {
  return {{"xyz_m", {xyz_m.x(), xyz_m.y(), xyz_m.z()}},
          {"rpy_deg", {rpy_deg.x(), rpy_deg.y(), rpy_deg.z()}}};
}

// mission.yaml's extrinsics of the mission below.
const Pose3 kTrueBodyLidarH = pose({0.5, 0.0, 1.0}, {0, 0, 0});
const Pose3 kTrueBodyLidarV = pose({0.3, 0.1, 0.8}, {0, 90, 0});
// The vehicle stands still at this pose while it scans, so any change of an extrinsic moves
// that sensor's map rigidly: map' = T_world_body * T' * T^-1 * T_world_body^-1 * map.
const Pose3 kWorldBody = pose({5.0, 2.0, -1.0}, {2, -3, 30});

std::string yaml_pose(const Pose3& T) {
  const Eigen::Quaterniond q(T.rotation());
  std::ostringstream out;
  out.precision(17);
  out << "{translation: [" << T.translation().x() << ", " << T.translation().y() << ", "
      << T.translation().z() << "], rotation_xyzw: [" << q.x() << ", " << q.y() << ", " << q.z()
      << ", " << q.w() << "]}";
  return out.str();
}

// Two lidars (the same 300-point scan, 6 sweeps each), an IMU without an extrinsic, and a
// `map` trajectory standing still at kWorldBody.
fs::path write_mission(const fs::path& dir) {
  if (fs::exists(dir / "mission.yaml")) return dir;
  fs::create_directories(dir / "scans");
  std::ofstream(dir / "mission.yaml") << "keel_mission: 1\nname: extrinsics\nplatform: usv\n"
                                      << "sensors:\n"
                                      << "  - {name: imu, type: imu, file: imu.csv, rate_hz: 10}\n"
                                      << "  - {name: lidar_h, type: lidar, scans: scans, rate_hz: "
                                         "10, T_body_sensor: "
                                      << yaml_pose(kTrueBodyLidarH) << "}\n"
                                      << "  - {name: lidar_v, type: lidar, scans: scans, rate_hz: "
                                         "10, T_body_sensor: "
                                      << yaml_pose(kTrueBodyLidarV) << "}\n"
                                      << "trajectories:\n  map: map.tum\n";
  std::ofstream imu(dir / "imu.csv");
  imu << "t,wx,wy,wz,ax,ay,az\n";
  for (int i = 0; i < 10; ++i) imu << "1700000000." << i << ",0,0,0,0,0,9.81\n";
  std::ostringstream points;
  for (int i = 0; i < 300; ++i)  // a spiral: no two points closer than a few cm
    points << 2.0 + 0.01 * i << " " << std::cos(0.37 * i) * (1.0 + 0.005 * i) << " "
           << std::sin(0.37 * i) * 0.8 << "\n";
  std::ofstream(dir / "scans" / "s.pcd")
      << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
         "WIDTH 300\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 300\nDATA ascii\n"
      << points.str();
  std::ofstream index(dir / "scans" / "index.csv");
  index << "t,file\n";
  for (int i = 1; i <= 6; ++i) index << "1700000000." << i << ",s.pcd\n";
  const Eigen::Quaterniond q(kWorldBody.rotation());
  const Eigen::Vector3d t = kWorldBody.translation();
  std::ofstream map(dir / "map.tum");
  map.precision(17);
  for (int i = 0; i < 10; ++i)
    map << "1700000000." << i << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " "
        << q.y() << " " << q.z() << " " << q.w() << "\n";
  return dir;
}

Pose3 extrinsic_of(const io::Mission& mission, const std::string& sensor) {
  const auto& e = *mission.sensor(sensor).T_body_sensor;
  return make_pose(Eigen::Quaterniond(e.rotation_xyzw[3], e.rotation_xyzw[0], e.rotation_xyzw[1],
                                      e.rotation_xyzw[2]),
                   Eigen::Vector3d(e.translation[0], e.translation[1], e.translation[2]));
}

std::string error_of(const json& calibration) {
  return keel::testing::error_of(
      [&] { load_job_mission(write_mission(temp_root() / "mission"), calibration); });
}

class JobExtrinsicsTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

TEST_F(JobExtrinsicsTest, OverridesReplaceAndComposeWithTheReference) {
  const fs::path dir = write_mission(temp_root() / "mission");
  {  // No overrides: the mission as uploaded.
    const io::Mission m = load_job_mission(dir, nullptr);
    EXPECT_TRUE(m.extrinsic_sources.empty());
    EXPECT_TRUE(extrinsic_of(m, "lidar_v").isApprox(kTrueBodyLidarV, 1e-12));
    const JobExtrinsics e = job_extrinsics(m);
    ASSERT_EQ(e.size(), 2u);  // the IMU has none
    EXPECT_EQ(e.at("lidar_h").source, "mission.yaml");
    EXPECT_EQ(e.at("lidar_v").source, "mission.yaml");
  }
  const Eigen::Vector3d xyz(0.2, -0.1, 0.4), rpy(5, 80, -10);
  {  // T_body_sensor replaces mission.yaml's.
    const io::Mission m =
        load_job_mission(dir, {{"lidar_v", {{"T_body_sensor", pose_json(xyz, rpy)}}}});
    EXPECT_TRUE(extrinsic_of(m, "lidar_v").isApprox(pose(xyz, rpy), 1e-12));
    EXPECT_TRUE(extrinsic_of(m, "lidar_h").isApprox(kTrueBodyLidarH, 1e-12));
    io::MissionReader reader(m);
    EXPECT_TRUE(reader.extrinsic("lidar_v")->isApprox(pose(xyz, rpy), 1e-12));
    const JobExtrinsics e = job_extrinsics(reader);
    EXPECT_EQ(e.at("lidar_v").source, "override T_body_sensor");
    EXPECT_EQ(e.at("lidar_h").source, "mission.yaml");
    const json section = calibration_report(e);
    EXPECT_EQ(section["lidar_v"]["source"], "override T_body_sensor");
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(section["lidar_v"]["xyz_m"][i].get<double>(), xyz[i], 1e-12);
      EXPECT_NEAR(section["lidar_v"]["rpy_deg"][i].get<double>(), rpy[i], 1e-9);
    }
  }
  {  // T_lidar_h_lidar_v composes with lidar_h's mission.yaml extrinsic.
    const io::Mission m =
        load_job_mission(dir, {{"lidar_v", {{"T_lidar_h_lidar_v", pose_json(xyz, rpy)}}}});
    EXPECT_TRUE(extrinsic_of(m, "lidar_v").isApprox(kTrueBodyLidarH * pose(xyz, rpy), 1e-12));
    EXPECT_EQ(job_extrinsics(m).at("lidar_v").source, "override T_lidar_h_lidar_v");
  }
  {  // ... and with lidar_h's own override when it has one.
    const Pose3 T_body_lidar_h = pose({1, 2, 3}, {0, 0, 45});
    const io::Mission m =
        load_job_mission(dir, {{"lidar_h", {{"T_body_sensor", pose_json({1, 2, 3}, {0, 0, 45})}}},
                               {"lidar_v", {{"T_lidar_h_lidar_v", pose_json(xyz, rpy)}}}});
    EXPECT_TRUE(extrinsic_of(m, "lidar_v").isApprox(T_body_lidar_h * pose(xyz, rpy), 1e-12));
    EXPECT_TRUE(extrinsic_of(m, "lidar_h").isApprox(T_body_lidar_h, 1e-12));
  }
  {  // A sensor without an extrinsic in mission.yaml takes one from its override.
    const io::Mission m = load_job_mission(
        dir,
        {{"imu",
          {{"T_lidar_v_imu", {{"translation", {0, 0, 1}}, {"rotation_xyzw", {0, 0, 0, 1}}}}}}});
    EXPECT_TRUE(
        extrinsic_of(m, "imu").isApprox(kTrueBodyLidarV * pose({0, 0, 1}, {0, 0, 0}), 1e-12));
  }
}

TEST_F(JobExtrinsicsTest, ErrorsNameTheOptionPathAndTheSensor) {
  const json p = pose_json({0, 0, 0}, {0, 0, 0});
  EXPECT_EQ(error_of({{"sonr", {{"T_body_sensor", p}}}}),
            "calibration.sonr: no sensor 'sonr' in the mission (sensors: imu, lidar_h, lidar_v)");
  EXPECT_EQ(error_of({{"lidar_v", {{"T_lidar_x_lidar_v", p}}}}),
            "calibration.lidar_v.T_lidar_x_lidar_v: no sensor 'lidar_x' in the mission (sensors: "
            "imu, lidar_h, lidar_v)");
  EXPECT_EQ(error_of({{"lidar_v", {{"T_imu_lidar_v", p}}}}),
            "calibration.lidar_v.T_imu_lidar_v: the reference 'imu' has no T_body_sensor (neither "
            "in mission.yaml nor in the bag's /tf_static)");
  EXPECT_EQ(
      error_of({{"lidar_h", {{"T_lidar_v_lidar_h", p}}}, {"lidar_v", {{"T_lidar_h_lidar_v", p}}}}),
      "calibration.lidar_h.T_lidar_v_lidar_h: the reference 'lidar_v' has a relative override "
      "itself (calibration.lidar_v.T_lidar_h_lidar_v); chains of relative overrides are "
      "refused: give lidar_v's T_body_sensor");
  EXPECT_EQ(error_of({{"lidar_v", {{"T_body_sensor", {{"xyz_m", {0, 0}}}}}}}),
            "calibration.lidar_v.T_body_sensor.xyz_m: expected 3 numbers, got 2 items");
}

// Every filter off, so the map holds every scan point once per sweep.
json raw_map_options() {
  const json no_filters = {{"scan_filters", json::array()},
                           {"intermediary_filters", json::array()},
                           {"final_filters", json::array()}};
  return {{"final_voxel_leaf_m", 0.0},
          {"sensor_filters", {{"lidar_h", no_filters}, {"lidar_v", no_filters}}},
          {"slam_sensor", "lidar_h"}};
}

JobResult run_job(const fs::path& work, const json& calibration) {
  JobSpec spec;
  spec.mission_dir = write_mission(temp_root() / "mission");
  spec.work_dir = work;
  spec.stages = {"ingest", "map"};
  spec.options = {{"map", raw_map_options()}};
  if (!calibration.is_null()) spec.options["calibration"] = calibration;
  return JobRunner().run(spec);
}

std::vector<Eigen::Vector3d> map_points(const fs::path& work, const std::string& sensor) {
  const PointCloud cloud = io::read_scan_file(work / map_ply_file(sensor), 0);
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : cloud.xyz) out.push_back(p.cast<double>());
  return out;
}

// The largest distance from a point of `b` to its nearest point of G * a (brute force).
double max_nearest_distance(const std::vector<Eigen::Vector3d>& b,
                            const std::vector<Eigen::Vector3d>& a, const Pose3& G) {
  double worst = 0.0;
  for (const auto& q : b) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : a) best = std::min(best, (G * p - q).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST_F(JobExtrinsicsTest, AnOverrideMovesTheSensorsMapByItsTransform) {
  const JobResult plain = run_job(temp_root() / "work_plain", nullptr);
  ASSERT_EQ(plain.outcome, JobOutcome::kSucceeded) << plain.error;
  const Eigen::Vector3d xyz(0.25, -0.15, 0.6), rpy(4, 70, -12);
  const JobResult moved = run_job(temp_root() / "work_override",
                                  {{"lidar_v", {{"T_lidar_h_lidar_v", pose_json(xyz, rpy)}}}});
  ASSERT_EQ(moved.outcome, JobOutcome::kSucceeded) << moved.error;

  // map' = T_world_body * T_body_lidar_v' * T_body_lidar_v^-1 * T_world_body^-1 * map.
  const Pose3 T_override = kTrueBodyLidarH * pose(xyz, rpy);
  const Pose3 G = kWorldBody * T_override * kTrueBodyLidarV.inverse() * kWorldBody.inverse();
  const auto a = map_points(temp_root() / "work_plain", "lidar_v");
  const auto b = map_points(temp_root() / "work_override", "lidar_v");
  ASSERT_EQ(a.size(), 6u * 300u);
  ASSERT_EQ(b.size(), a.size());
  EXPECT_LT(max_nearest_distance(b, a, G), 2e-5);  // float32 map points, ~10 m from the origin
  EXPECT_GT(max_nearest_distance(b, a, Pose3::Identity()), 0.5);
  // The other lidar's map does not move.
  const auto h_a = map_points(temp_root() / "work_plain", "lidar_h");
  const auto h_b = map_points(temp_root() / "work_override", "lidar_h");
  ASSERT_EQ(h_a.size(), h_b.size());
  EXPECT_LT(max_nearest_distance(h_b, h_a, Pose3::Identity()), 1e-6);

  // report.json: the sources and the extrinsic used; ingest names the override too.
  std::ifstream in(temp_root() / "work_override" / "report.json");
  const json report = json::parse(in);
  EXPECT_EQ(report["calibration"]["lidar_v"]["source"], "override T_lidar_h_lidar_v");
  EXPECT_EQ(report["calibration"]["lidar_h"]["source"], "mission.yaml");
  EXPECT_FALSE(report["calibration"].contains("imu"));
  const auto& t = report["calibration"]["lidar_v"]["T_body_sensor"]["translation"];
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(t[i].get<double>(), T_override.translation()[i], 1e-12);
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["lidar_v"]["extrinsic"],
            "override T_lidar_h_lidar_v");
  std::ifstream plain_in(temp_root() / "work_plain" / "report.json");
  EXPECT_EQ(json::parse(plain_in)["calibration"]["lidar_v"]["source"], "mission.yaml");
  std::ifstream html(temp_root() / "work_override" / "report.html");
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("id=\"calibration\""), std::string::npos);
  EXPECT_NE(page.find("override T_lidar_h_lidar_v"), std::string::npos);
}

TEST_F(JobExtrinsicsTest, ABadOverrideFailsTheJobNamingTheSensor) {
  const JobResult result = run_job(
      temp_root() / "work_bad", {{"sonr", {{"T_body_sensor", pose_json({0, 0, 0}, {0, 0, 0})}}}});
  EXPECT_EQ(result.outcome, JobOutcome::kFailed);
  EXPECT_EQ(result.error,
            "ingest: calibration.sonr: no sensor 'sonr' in the mission (sensors: imu, lidar_h, "
            "lidar_v)");
}

}  // namespace
}  // namespace keel::pipeline
