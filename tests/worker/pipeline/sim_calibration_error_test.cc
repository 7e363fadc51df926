// keel-sim's calibration_error (issue 31, Build 4): mission.yaml declares T_true * T_error for
// the perturbed sensors while the data follow T_true (kept in ground_truth/truth.yaml), and a
// map stage given the truth back as a job override builds the very map of an unperturbed
// mission.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/error_of.h"
#include "tests/sim/calibration_error.h"
#include "tests/worker/pipeline/sim_mission.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/stages/map/artifacts.h"
#include "worker/stages/map/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr uint64_t kSeed = 5;
constexpr double kDeg = M_PI / 180.0;
const char* const kLidarError = R"({"xyz_m":[0.05,-0.02,0.01],"rpy_deg":[1,-2,0.5]})";
const char* const kSonarError = R"({"xyz_m":[0.1,0,-0.03],"rpy_deg":[0,3,-1]})";

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_sim_calibration_" + std::to_string(::getpid()));
}

fs::path simulate(const std::string& name, std::vector<std::string> settings) {
  const fs::path dir = temp_root() / name;
  if (fs::exists(dir / "mission.yaml")) return dir;
  sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.seed = kSeed;
  o.out_dir = dir.string();
  o.duration_s = 8.0;
  o.sensors = {"lidar_h", "lidar_v", "sonar"};
  o.settings = std::move(settings);
  sim::run_simulation(o);
  return dir;
}

fs::path plain_mission() { return simulate("plain", {}); }
fs::path perturbed_mission() {
  return simulate("perturbed", {std::string("calibration_error.lidar_v=") + kLidarError,
                                std::string("calibration_error.sonar=") + kSonarError});
}

Pose3 yaml_pose(const YAML::Node& node) {
  const auto t = node["translation"].as<std::vector<double>>();
  const auto q = node["rotation_xyzw"].as<std::vector<double>>();
  return make_pose(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
}

Pose3 declared(const fs::path& mission, const std::string& sensor) {
  for (const auto& s : YAML::LoadFile((mission / "mission.yaml").string())["sensors"])
    if (s["name"].as<std::string>() == sensor) return yaml_pose(s["T_body_sensor"]);
  throw std::runtime_error("no sensor " + sensor);
}

Pose3 error_pose(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy_deg) {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(rpy_deg.z() * kDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy_deg.y() * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy_deg.x() * kDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = xyz;
  return T;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

class SimCalibrationErrorTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

TEST_F(SimCalibrationErrorTest, MissionDeclaresTruthTimesErrorAndKeepsTheTruth) {
  const fs::path plain = plain_mission(), perturbed = perturbed_mission();
  const YAML::Node truth = YAML::LoadFile((perturbed / "ground_truth" / "truth.yaml").string());
  const Pose3 T_true_lidar_v = yaml_pose(truth["extrinsics"]["lidar_v"]);
  const Pose3 T_true_sonar = yaml_pose(truth["extrinsics"]["sonar"]);
  // The truth is the unperturbed mission's extrinsic.
  EXPECT_TRUE(T_true_lidar_v.isApprox(declared(plain, "lidar_v"), 1e-9));
  EXPECT_TRUE(T_true_sonar.isApprox(declared(plain, "sonar"), 1e-9));
  // Declared = truth * error (mission.yaml keeps 10 digits).
  const Pose3 lidar_error = error_pose({0.05, -0.02, 0.01}, {1, -2, 0.5});
  const Pose3 sonar_error = error_pose({0.1, 0, -0.03}, {0, 3, -1});
  EXPECT_TRUE(declared(perturbed, "lidar_v").isApprox(T_true_lidar_v * lidar_error, 1e-8));
  EXPECT_TRUE(declared(perturbed, "sonar").isApprox(T_true_sonar * sonar_error, 1e-8));
  EXPECT_FALSE(declared(perturbed, "lidar_v").isApprox(T_true_lidar_v, 1e-3));
  EXPECT_TRUE(declared(perturbed, "lidar_h").isApprox(declared(plain, "lidar_h"), 1e-12));
  EXPECT_TRUE(yaml_pose(truth["calibration_error"]["sonar"]).isApprox(sonar_error, 1e-8));
  // The data follow the truth: the same scans, byte for byte.
  EXPECT_EQ(slurp(plain / "lidar_v" / "index.csv"), slurp(perturbed / "lidar_v" / "index.csv"));
  for (const auto& entry : fs::directory_iterator(plain / "sonar"))
    EXPECT_EQ(slurp(entry.path()), slurp(perturbed / "sonar" / entry.path().filename()))
        << entry.path();
}

TEST_F(SimCalibrationErrorTest, TheTruthAsAnOverrideGivesTheUnperturbedMap) {
  const fs::path plain = plain_mission(), perturbed = perturbed_mission();
  const YAML::Node truth = YAML::LoadFile((perturbed / "ground_truth" / "truth.yaml").string());
  auto truth_json = [&](const std::string& sensor) {
    const YAML::Node e = truth["extrinsics"][sensor];
    return json{{"translation", e["translation"].as<std::vector<double>>()},
                {"rotation_xyzw", e["rotation_xyzw"].as<std::vector<double>>()}};
  };
  const json options = {{"threads", 1}};
  auto run = [&](const fs::path& mission, const json& calibration, const std::string& work) {
    StageContext context;
    context.mission_dir = mission;
    context.work_dir = temp_root() / work;
    context.options = options;
    context.calibration = calibration;
    fs::create_directories(context.work_dir);
    make_map_stage()->run(context);
    return context.work_dir;
  };
  const fs::path a = run(plain, nullptr, "work_plain");
  const fs::path b = run(perturbed,
                         {{"lidar_v", {{"T_body_sensor", truth_json("lidar_v")}}},
                          {"sonar", {{"T_body_sensor", truth_json("sonar")}}}},
                         "work_truth_override");
  const fs::path c = run(perturbed, nullptr, "work_perturbed");
  for (const std::string sensor : {"lidar_h", "lidar_v", "sonar", "combined"}) {
    const std::string map_a = slurp(a / map_ply_file(sensor));
    ASSERT_GT(map_a.size(), 1000u) << sensor;
    EXPECT_TRUE(map_a == slurp(b / map_ply_file(sensor))) << sensor;
    if (sensor != "lidar_h") {
      EXPECT_FALSE(map_a == slurp(c / map_ply_file(sensor))) << sensor;
    }
  }
}

// A bag mission whose mission.yaml has no T_body_sensor: the extrinsics come from /tf_static,
// where keel-sim declared lidar_v's with its error; a relative override resolves against it.
TEST_F(SimCalibrationErrorTest, TfStaticDeclaresTheErrorAndResolvesReferences) {
  const fs::path sim_dir = temp_root() / "bag_sim";
  sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.seed = kSeed;
  o.out_dir = sim_dir.string();
  o.duration_s = 2.0;
  o.sensors = {"lidar_h", "lidar_v"};
  o.write_bag = true;
  o.settings = {std::string("calibration_error.lidar_v=") + kLidarError};
  sim::run_simulation(o);
  const fs::path dir = temp_root() / "bag_mission";
  fs::create_directories(dir);
  for (const auto& entry : fs::directory_iterator(sim_dir))
    if (entry.path().extension() != ".yaml")
      fs::create_symlink(entry.path(), dir / entry.path().filename());
  YAML::Node manifest = YAML::LoadFile((sim_dir / "mission_bag.yaml").string());
  for (auto sensor : manifest["sensors"]) sensor.remove("T_body_sensor");
  std::ofstream(dir / "mission.yaml") << YAML::Dump(manifest) << "\n";

  const YAML::Node truth = YAML::LoadFile((sim_dir / "ground_truth" / "truth.yaml").string());
  const Pose3 T_true_lidar_h = yaml_pose(truth["extrinsics"]["lidar_h"]);
  const Pose3 T_true_lidar_v = yaml_pose(truth["extrinsics"]["lidar_v"]);
  const Pose3 lidar_error = error_pose({0.05, -0.02, 0.01}, {1, -2, 0.5});
  {
    const JobExtrinsics e = job_extrinsics(load_job_mission(dir, nullptr));
    EXPECT_EQ(e.at("lidar_h").source, "/tf_static");
    EXPECT_EQ(e.at("lidar_v").source, "/tf_static");
    EXPECT_TRUE(e.at("lidar_h").T_body_sensor.isApprox(T_true_lidar_h, 1e-9));
    EXPECT_TRUE(e.at("lidar_v").T_body_sensor.isApprox(T_true_lidar_v * lidar_error, 1e-9));
  }
  const Pose3 relative = error_pose({0.2, 0, 0.2}, {0, 90, 0});
  const io::Mission m = load_job_mission(
      dir,
      {{"lidar_v", {{"T_lidar_h_lidar_v", {{"xyz_m", {0.2, 0, 0.2}}, {"rpy_deg", {0, 90, 0}}}}}}});
  io::MissionReader reader(m);
  const JobExtrinsics e = job_extrinsics(reader);
  EXPECT_EQ(e.at("lidar_h").source, "/tf_static");
  EXPECT_EQ(e.at("lidar_v").source, "override T_lidar_h_lidar_v");
  EXPECT_TRUE(e.at("lidar_v").T_body_sensor.isApprox(T_true_lidar_h * relative, 1e-9));
  EXPECT_TRUE(reader.extrinsic("lidar_v")->isApprox(T_true_lidar_h * relative, 1e-9));
}

TEST(SimCalibrationErrorSettings, ParseAndErrors) {
  std::vector<std::string> settings = {
      "lidar.points_per_ring=300",
      R"(calibration_error.sonar={"xyz_m":[1,0,0],"rpy_deg":[0,0,90]})"};
  const sim::CalibrationErrors errors = sim::take_calibration_errors(&settings);
  EXPECT_EQ(settings, std::vector<std::string>{"lidar.points_per_ring=300"});
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_TRUE(errors.at("sonar").isApprox(error_pose({1, 0, 0}, {0, 0, 90}), 1e-12));
  std::vector<std::string> bad = {"calibration_error.sonar={\"xyz_m\":[1,0]}"};
  EXPECT_EQ(keel::testing::error_of([&] { sim::take_calibration_errors(&bad); }),
            "--set calibration_error.sonar.xyz_m: expected 3 numbers, got 2 items");
  sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.out_dir = (temp_root() / "bad").string();
  o.duration_s = 1.0;
  o.settings = {R"(calibration_error.sonr={"xyz_m":[0,0,0],"rpy_deg":[0,0,0]})"};
  EXPECT_EQ(keel::testing::error_of([&] { sim::run_simulation(o); }),
            "--set calibration_error.sonr: scenario usv-bridge has no sensor 'sonr'");
}

}  // namespace
}  // namespace keel::pipeline
