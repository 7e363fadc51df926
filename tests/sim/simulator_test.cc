#include "tests/sim/simulator.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <iterator>

namespace keel::sim {
namespace {
namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

size_t count_lines(const fs::path& path) {
  const std::string text = slurp(path);
  return std::count(text.begin(), text.end(), '\n');
}

class SimulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("keel_sim_test_" + std::to_string(::getpid()));
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  SimOptions corridor(uint64_t seed, const std::string& dir) {
    SimOptions o;
    o.scenario = "usv-corridor";
    o.seed = seed;
    o.out_dir = (root_ / dir).string();
    o.duration_s = 3.0;
    o.settings = {"lidar.points_per_ring=300", "camera.rate_hz=1"};
    return o;
  }
  fs::path root_;
};

TEST_F(SimulatorTest, SameSeedSameBytesOtherSeedOtherBytes) {
  run_simulation(corridor(5, "a"));
  SimOptions b = corridor(5, "b");
  b.threads = 1;  // thread count must not matter
  run_simulation(b);
  run_simulation(corridor(6, "c"));
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root_ / "a")) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), root_ / "a");
    ASSERT_TRUE(fs::exists(root_ / "b" / rel)) << rel;
    EXPECT_EQ(slurp(entry.path()), slurp(root_ / "b" / rel)) << rel;
    ++files;
  }
  EXPECT_GT(files, 50u);
  EXPECT_NE(slurp(root_ / "a" / "imu.csv"), slurp(root_ / "c" / "imu.csv"));
  EXPECT_NE(slurp(root_ / "a" / "lidar_h" / "000005.pcd"),
            slurp(root_ / "c" / "lidar_h" / "000005.pcd"));
  EXPECT_NE(slurp(root_ / "a" / "odometry.tum"), slurp(root_ / "c" / "odometry.tum"));
}

TEST_F(SimulatorTest, ManifestNamesFilesThatExist) {
  SimOptions o = corridor(1, "m");
  o.dvl_scale = 1.02;
  run_simulation(o);
  const fs::path dir = root_ / "m";
  const YAML::Node mission = YAML::LoadFile((dir / "mission.yaml").string());
  EXPECT_EQ(mission["keel_mission"].as<int>(), 1);
  EXPECT_EQ(mission["platform"].as<std::string>(), "usv");
  ASSERT_EQ(mission["sensors"].size(), 7u);
  for (const auto& sensor : mission["sensors"]) {
    for (const char* key : {"file", "scans", "images"})
      if (sensor[key]) {
        EXPECT_TRUE(fs::exists(dir / sensor[key].as<std::string>())) << sensor[key];
      }
    EXPECT_EQ(sensor["T_body_sensor"]["rotation_xyzw"].size(), 4u);
  }
  for (const char* key : {"map", "odometry", "ground_truth"})
    EXPECT_TRUE(fs::exists(dir / mission["trajectories"][key].as<std::string>()));
  const YAML::Node truth = YAML::LoadFile((dir / "ground_truth" / "truth.yaml").string());
  EXPECT_DOUBLE_EQ(truth["dvl_scale"].as<double>(), 1.02);
  EXPECT_TRUE(truth["extrinsics"]["dvl"]);
  // 200 Hz IMU over 3 s: 601 samples plus the header.
  EXPECT_EQ(count_lines(dir / "imu.csv"), 602u);
  EXPECT_EQ(count_lines(dir / "lidar_h" / "index.csv"), 31u);  // sweeps that end by 3 s
}

TEST_F(SimulatorTest, BagCarriesTheSameData) {
  SimOptions o = corridor(2, "bag");
  o.write_bag = true;
  run_simulation(o);
  const fs::path dir = root_ / "bag";
  rosbag::Bag bag((dir / "mission.bag").string(), rosbag::bagmode::Read);
  std::map<std::string, size_t> counts;
  for (const auto& m : rosbag::View(bag)) ++counts[m.getTopic()];
  EXPECT_EQ(counts["/imu/data"], count_lines(dir / "imu.csv") - 1);
  EXPECT_EQ(counts["/lidar_h/points"], count_lines(dir / "lidar_h" / "index.csv") - 1);
  EXPECT_EQ(counts["/cam0/image_raw"], count_lines(dir / "cam0" / "index.csv") - 1);
  EXPECT_EQ(counts["/slam/keyframes"], count_lines(dir / "map_poses.tum"));
  const YAML::Node manifest = YAML::LoadFile((dir / "mission_bag.yaml").string());
  EXPECT_EQ(manifest["bag"].as<std::string>(), "mission.bag");
  EXPECT_EQ(manifest["trajectories"]["odometry"]["topic"].as<std::string>(), "/slam/odometry");
  for (const auto& sensor : manifest["sensors"])
    if (sensor["topic"]) {
      EXPECT_GT(counts[sensor["topic"].as<std::string>()], 0u) << sensor["name"];
    }
}

TEST_F(SimulatorTest, BadOptionsAreRejectedWithTheirName) {
  SimOptions o = corridor(1, "bad");
  o.settings = {"lidar.nonsense=3"};
  EXPECT_THROW(
      {
        try {
          run_simulation(o);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("lidar.nonsense"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  o.settings = {"imu.rate_hz=abc"};
  EXPECT_THROW(run_simulation(o), std::invalid_argument);
  o.settings = {};
  o.sensors = {"lidar_h", "sonarr"};
  EXPECT_THROW(run_simulation(o), std::invalid_argument);
  o.sensors = {};
  o.scenario = "moon-base";
  EXPECT_THROW(run_simulation(o), std::invalid_argument);
}

// A range sigma goes into mission.yaml, whose readers refuse 0: keel-sim refuses it first.
TEST(SimulatorSettings, RangeSigmaMustBePositive) {
  for (const char* key : {"lidar.range_sigma", "sonar.range_sigma", "dvl.range_sigma"}) {
    SensorSettings sensors;
    ScenarioOptions options;
    try {
      apply_settings({std::string(key) + "=0"}, &sensors, &options);
      ADD_FAILURE() << key << "=0 was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(apply_settings({std::string(key) + "=0.0001"}, &sensors, &options)) << key;
  }
}

}  // namespace
}  // namespace keel::sim
