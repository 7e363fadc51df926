#include "worker/io/mission.h"

#include <gtest/gtest.h>

#include "io_test_util.h"
#include "proto/contract_error.h"
#include "test_bundle.h"
#include "worker/io/mission_reader.h"
#include "worker/io/yaml_json.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(YamlJson, ScalarsFollowTheCoreSchema) {
  const auto j =
      yaml_to_json("a: 1\nb: 2.5\nc: '3'\nd: true\ne: ~\nf: [1, x]\ng: 1e-3\nh: -7\n", "t.yaml");
  EXPECT_TRUE(j["a"].is_number_integer());
  EXPECT_EQ(j["b"].get<double>(), 2.5);
  EXPECT_TRUE(j["c"].is_string());
  EXPECT_EQ(j["d"], true);
  EXPECT_TRUE(j["e"].is_null());
  EXPECT_EQ(j["f"][1], "x");
  EXPECT_EQ(j["g"].get<double>(), 1e-3);
  EXPECT_EQ(j["h"].get<int>(), -7);
}

TEST(YamlJson, SyntaxErrorsAndDuplicateKeysNameLine) {
  expect_error([] { yaml_to_json("a: 1\nb: [1, 2\n", "m.yaml"); }, {"m.yaml:"});
  expect_error([] { yaml_to_json("a: 1\nb: 2\na: 3\n", "m.yaml"); },
               {"m.yaml:3:", "duplicate key 'a'"});
}

TEST(Manifest, DefaultsAreSeedTableOneAndRoundTrip) {
  const auto j = yaml_to_json(testing::bundle_yaml(), "mission.yaml");
  const auto m = proto::MissionManifest::from_json(j);
  EXPECT_EQ(m.name, "test-bundle");
  EXPECT_EQ(m.body_frame, "base_link");
  ASSERT_EQ(m.sensors.size(), 4u);
  EXPECT_EQ(m.sensors[0].noise.imu.gyro_noise_density, 5.7e-4);  // seed 000 Table I
  EXPECT_EQ(m.sensors[0].noise.imu.accel_random_walk, 2.4e-6);
  EXPECT_EQ(m.sensors[1].noise.dvl.velocity_sigma_rel, 2.0e-3);  // given in the yaml
  EXPECT_EQ(m.sensors[1].noise.dvl.bias_random_walk_rel, 1.0e-4);
  EXPECT_EQ(m.sensors[2].noise.range.range_sigma, 0.01);
  EXPECT_EQ(m.sensors[2].point_time->unit, proto::TimeUnit::kSeconds);
  EXPECT_EQ(m.sensors[3].camera->width, 8);
  EXPECT_EQ(m.trajectories.at("odometry").file, "odometry.tum");
  const auto back = proto::MissionManifest::from_json(nlohmann::json::parse(m.to_json().dump()));
  EXPECT_EQ(back.to_json(), m.to_json());
}

TEST(Manifest, ErrorsNameTheFieldPath) {
  const auto base = testing::bundle_yaml();
  auto parse = [](const std::string& yaml) {
    proto::MissionManifest::from_json(yaml_to_json(yaml, "mission.yaml"));
  };
  expect_error(
      [&] {
        parse(replace(base, "rotation_xyzw: [0, 0, 0, 1]}\n  - name: cam0",
                      "rotation_xyzw: [0, 0, 1]}\n  - name: cam0"));
      },
      {"sensors[2].T_body_sensor.rotation_xyzw", "expected 4 numbers, got 3"});
  expect_error(
      [&] { parse(replace(base, "rate_hz: 20\n    T_body", "rate_hz: fast\n    T_body")); },
      {"sensors[1].rate_hz", "expected number, got string"});
  expect_error(
      [&] { parse(replace(base, "    file: dvl.csv\n", "    file: dvl.csv\n    colour: red\n")); },
      {"sensors[1].colour: unknown field"});
  expect_error([&] { parse(replace(base, "name: test-bundle\n", "")); },
               {"name: missing required field"});
  expect_error(
      [&] { parse(replace(base, "noise: {velocity_sigma_rel", "noise: {gyro_noise_density")); },
      {"sensors[1].noise.gyro_noise_density: unknown field"});
  expect_error(
      [&] { parse(replace(base, "    file: dvl.csv\n", "    file: dvl.csv\n    topic: /dvl\n")); },
      {"sensors[1]", "exactly one of file, scans, images, topic"});
  expect_error([&] { parse(replace(base, "name: dvl\n", "name: imu\n")); },
               {"sensors[1].name", "repeated"});
  expect_error([&] { parse(replace(base, "unit: s,", "unit: seconds,")); },
               {"sensors[2].point_time.unit", "unknown time unit 'seconds'"});
}

TEST(Mission, LoadsAndResolvesPaths) {
  TempDir dir;
  testing::write_bundle(dir.path());
  const Mission m = load_mission(dir.path());
  EXPECT_EQ(m.manifest.sensors.size(), 4u);
  EXPECT_EQ(m.sensor_path("imu"), dir / "imu.csv");
  EXPECT_EQ(m.sensor_path("lidar_h"), dir / "lidar_h");
  EXPECT_EQ(m.trajectory_paths.at("map"), dir / "map_poses.tum");
  EXPECT_TRUE(m.bag_path.empty());
}

TEST(Mission, MissingFileNamesFieldAndPath) {
  TempDir dir;
  testing::write_bundle(dir.path());
  std::filesystem::remove(dir / "dvl.csv");
  expect_error([&] { load_mission(dir.path()); },
               {"mission.yaml: sensors[1].file: 'dvl.csv' not found", (dir / "dvl.csv").string()});
  testing::write_bundle(dir.path());
  std::filesystem::remove(dir / "lidar_h" / "index.csv");
  expect_error([&] { load_mission(dir.path()); }, {"sensors[2].scans", "no index.csv"});
  testing::write_bundle(dir.path());
  std::filesystem::remove(dir / "map_poses.tum");
  expect_error([&] { load_mission(dir.path()); }, {"trajectories.map: 'map_poses.tum' not found"});
}

TEST(Mission, UnknownSensorTypeNamesFieldAndKnownTypes) {
  TempDir dir;
  testing::write_bundle(dir.path());
  write_text(dir / "mission.yaml", replace(testing::bundle_yaml(), "type: dvl", "type: doppler"));
  expect_error([&] { load_mission(dir.path()); },
               {"mission.yaml: sensors[1].type", "unknown sensor type 'doppler'",
                "imu, dvl, dvl_ranges, lidar, sonar, camera, depth, servo"});
}

TEST(Mission, BadQuaternionNamesField) {
  TempDir dir;
  testing::write_bundle(dir.path());
  write_text(
      dir / "mission.yaml",
      replace(testing::bundle_yaml(), "translation: [0, 0, -0.3], rotation_xyzw: [0, 0, 0, 1]",
              "translation: [0, 0, -0.3], rotation_xyzw: [0, 0, 0.5, 1]"));
  expect_error([&] { load_mission(dir.path()); },
               {"sensors[1].T_body_sensor.rotation_xyzw", "unit quaternion", "|q| = 1.118"});
}

TEST(Mission, PathsMayNotLeaveTheBundleAndMissingManifestIsNamed) {
  TempDir dir;
  testing::write_bundle(dir.path());
  write_text(dir / "mission.yaml",
             replace(testing::bundle_yaml(), "file: imu.csv", "file: ../../etc/passwd"));
  expect_error([&] { load_mission(dir.path()); },
               {"sensors[0].file", "relative path inside the bundle"});
  expect_error([&] { load_mission(dir / "nowhere"); }, {"mission.yaml: not found"});
}

TEST(MissionReader, ReadsEverySourceOfTheFileBundle) {
  TempDir dir;
  const auto figures = testing::write_bundle(dir.path());
  MissionReader reader(load_mission(dir.path()));
  EXPECT_EQ(reader.read_imu("imu").size(), figures.imu_samples);
  EXPECT_EQ(reader.read_dvl("dvl").size(), figures.dvl_samples);
  expect_error([&] { reader.read_dvl("imu"); }, {"sensor 'imu' is of type imu, not dvl"});
  expect_error([&] { reader.read_imu("gyro"); }, {"no sensor 'gyro'", "imu, dvl, lidar_h, cam0"});
  auto scans = reader.open_scans("lidar_h");
  ASSERT_EQ(scans->size(), figures.scans);
  PointCloud cloud;
  for (size_t k = 0; k < figures.scans; ++k) {
    ASSERT_TRUE(scans->next(cloud));
    EXPECT_EQ(cloud.size(), figures.points_per_scan_base + 10 * k);
    EXPECT_EQ(cloud.t_ns, testing::kT0 + static_cast<TimeNs>(k) * 100000000);
    EXPECT_EQ(cloud.frame, "lidar_h");
    EXPECT_NEAR(cloud.time_s.back(), 0.1, 1e-6);
    EXPECT_EQ(cloud.xyz[7], Eigen::Vector3f(7, static_cast<float>(k), 1));
  }
  EXPECT_FALSE(scans->next(cloud));
  auto images = reader.open_images("cam0");
  ImageFrame frame;
  ASSERT_TRUE(images->next(frame, true));
  ASSERT_TRUE(images->next(frame, true));
  EXPECT_EQ(frame.width, 8);
  EXPECT_EQ(frame.height, 6);
  EXPECT_EQ(frame.channels, 1);
  EXPECT_EQ(frame.pixels.at(17), 40);
  EXPECT_EQ(reader.read_trajectory("odometry").size(), figures.odometry_poses);
  const auto T = reader.extrinsic("dvl");
  ASSERT_TRUE(T);
  EXPECT_EQ(T->translation(), Eigen::Vector3d(0, 0, -0.3));
}

}  // namespace
}  // namespace keel::io

namespace keel::io {
namespace {

// Seed 001's servo tray: a servo with an axis, and tray sensors naming it.
TEST(Manifest, ServoTrayFieldsRoundTripAndAreChecked) {
  const nlohmann::json servo = {{"name", "servo"},
                                {"type", "servo"},
                                {"file", "servo.csv"},
                                {"rate_hz", 20},
                                {"axis", {0.0, -2.0, 0.0}}};
  nlohmann::json dvl = {{"name", "dvl"},
                        {"type", "dvl"},
                        {"file", "dvl.csv"},
                        {"rate_hz", 20},
                        {"mounted_on", "servo"}};
  nlohmann::json doc = {{"keel_mission", 1}, {"name", "tray"}, {"sensors", {servo, dvl}}};
  expect_error([&] { proto::MissionManifest::from_json(doc); }, {"sensors[0].axis", "unit vector"});
  doc["sensors"][0]["axis"] = {0.0, -1.0, 0.0};
  const auto m = proto::MissionManifest::from_json(doc);
  ASSERT_TRUE(m.sensors[0].axis.has_value());
  EXPECT_EQ((*m.sensors[0].axis)[1], -1.0);
  EXPECT_EQ(m.sensors[1].mounted_on, "servo");
  EXPECT_EQ(proto::MissionManifest::from_json(m.to_json()).to_json(), m.to_json());

  doc["sensors"][1]["mounted_on"] = "imu";
  expect_error([&] { proto::MissionManifest::from_json(doc); },
               {"sensors[1].mounted_on", "'imu' is not a servo"});
  doc["sensors"][1]["mounted_on"] = "servo";
  doc["sensors"][1]["axis"] = {0.0, 0.0, 1.0};
  expect_error([&] { proto::MissionManifest::from_json(doc); },
               {"sensors[1].axis", "only servo sensors"});
}

}  // namespace
}  // namespace keel::io
