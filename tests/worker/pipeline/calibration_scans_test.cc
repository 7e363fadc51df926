// calibration_scans.bin (docs/calibration.md) read back by hand, byte by byte as the document
// says, and the keyframe scans of a keel-sim usv-bridge mission: chosen as a brute-force search
// over every scan stamp would choose them, and placed where the other sensor sees the same
// structure.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "tests/worker/pipeline/sim_mission.h"
#include "worker/io/mission.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/calibrate/artifacts.h"
#include "worker/stages/calibrate/keyframe_scans.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("keel-calibration-scans-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

CalibrationScans example() {
  CalibrationScans scans;
  scans.reference = "lidar_h";
  scans.t0_s = 1700000000.25;
  scans.keyframes_t_s = {0.0, 1.0, 2.0};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (const char* name : {"lidar_h", "sonar"}) {
    CalibrationSensorScans sensor{
        name,
        name[0] == 'l' ? "lidar" : "sonar",
        make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                  Eigen::Vector3d(0.1, -0.2, 0.3)),
        "mission.yaml",
        {}};
    for (size_t j = 0; j < 3; ++j) {
      if (j == 1 && sensor.type == "sonar") continue;  // a keyframe without a scan
      CalibrationScan scan;
      scan.keyframe = j;
      scan.t_s = static_cast<double>(j) + 0.01;
      scan.T_world_body.translation() = Eigen::Vector3d(double(j), 2.0, 0.0);
      for (int i = 0; i < 37 + int(j); ++i) scan.points.emplace_back(u(rng), u(rng), u(rng));
      sensor.scans.push_back(scan);
    }
    scans.sensors.push_back(sensor);
  }
  return scans;
}

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(CalibrationScans, FileIsTheDocumentedLayout) {
  const fs::path path = scratch("layout") / kCalibrationScansFile;
  const CalibrationScans scans = example();
  write_calibration_scans(path, scans);
  const std::string bytes = file_bytes(path);
  ASSERT_GE(bytes.size(), 16u);
  EXPECT_EQ(bytes.substr(0, 8), "KEELCAL1");
  uint64_t length = 0;
  for (int i = 7; i >= 0; --i) length = (length << 8) | static_cast<unsigned char>(bytes[8 + i]);
  EXPECT_EQ((16 + length) % 4, 0u);
  const auto index = nlohmann::json::parse(bytes.substr(16, length));
  EXPECT_EQ(index["format"], "keel-calibration-scans");
  EXPECT_EQ(index["reference"], "lidar_h");
  EXPECT_DOUBLE_EQ(index["t0_s"].get<double>(), 1700000000.25);
  ASSERT_EQ(index["sensors"].size(), 2u);
  // Blocks follow the index, contiguous in sensor then keyframe order, 12 bytes a point.
  uint64_t expected_offset = 16 + length;
  for (size_t s = 0; s < 2; ++s) {
    const auto& sensor = index["sensors"][s];
    ASSERT_EQ(sensor["scans"].size(), scans.sensors[s].scans.size());
    for (size_t k = 0; k < sensor["scans"].size(); ++k) {
      const auto& scan = sensor["scans"][k];
      const auto& truth = scans.sensors[s].scans[k];
      EXPECT_EQ(scan["offset"].get<uint64_t>(), expected_offset);
      EXPECT_EQ(scan["count"].get<size_t>(), truth.points.size());
      EXPECT_EQ(scan["keyframe"].get<size_t>(), truth.keyframe);
      float last[3];
      std::memcpy(last, bytes.data() + expected_offset + 12 * (truth.points.size() - 1), 12);
      EXPECT_EQ(last[0], truth.points.back().x());
      EXPECT_EQ(last[2], truth.points.back().z());
      EXPECT_DOUBLE_EQ(scan["T_world_body"]["translation"][0].get<double>(),
                       truth.T_world_body.translation().x());
      expected_offset += 12 * truth.points.size();
    }
  }
  EXPECT_EQ(expected_offset, bytes.size());
}

TEST(CalibrationScans, ReadsBackWhatWasWritten) {
  const fs::path path = scratch("roundtrip") / kCalibrationScansFile;
  const CalibrationScans scans = example();
  write_calibration_scans(path, scans);
  const CalibrationScans back = read_calibration_scans(path);
  EXPECT_EQ(back.reference, scans.reference);
  EXPECT_EQ(back.keyframes_t_s, scans.keyframes_t_s);
  ASSERT_EQ(back.sensors.size(), scans.sensors.size());
  for (size_t s = 0; s < scans.sensors.size(); ++s) {
    EXPECT_EQ(back.sensors[s].name, scans.sensors[s].name);
    EXPECT_TRUE(back.sensors[s].T_body_sensor.isApprox(scans.sensors[s].T_body_sensor, 1e-12));
    ASSERT_EQ(back.sensors[s].scans.size(), scans.sensors[s].scans.size());
    for (size_t k = 0; k < scans.sensors[s].scans.size(); ++k)
      EXPECT_EQ(back.sensors[s].scans[k].points, scans.sensors[s].scans[k].points);
  }
}

TEST(CalibrationScans, TruncatedOrForeignFilesAreRefused) {
  const fs::path dir = scratch("bad");
  write_calibration_scans(dir / "good.bin", example());
  const std::string bytes = file_bytes(dir / "good.bin");
  std::ofstream(dir / "short.bin", std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  std::ofstream(dir / "foreign.bin", std::ios::binary) << "PLY\nformat binary\n........";
  try {
    read_calibration_scans(dir / "short.bin");
    FAIL() << "a truncated file was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("out of bounds"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("short.bin"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_calibration_scans(dir / "foreign.bin"), std::runtime_error);
}

// The nearest scan of each sensor per keyframe, found by brute force over every scan stamp.
TEST(KeyframeScans, NearestScanPerKeyframeDeskewedAndPlaced) {
  const fs::path dir =
      testing::simulate(scratch("sim"), "usv-bridge", 3, 12.0, {"lidar_h", "lidar_v"});
  io::MissionReader reader(io::load_mission(dir));
  const Trajectory truth = reader.read_trajectory("ground_truth");
  std::vector<TimeNs> keyframes;
  for (const auto& pose : reader.read_trajectory("map")) keyframes.push_back(pose.t_ns);
  ASSERT_GE(keyframes.size(), 4u);
  std::vector<SensorToCollect> sensors;
  for (const std::string name : {"lidar_h", "lidar_v"})
    sensors.push_back({name, "lidar", *reader.extrinsic(name), "mission.yaml"});
  const CalibrationScans scans =
      collect_keyframe_scans(reader, keyframes, truth, sensors, "lidar_h", KeyframeScanOptions{});
  ASSERT_EQ(scans.sensors.size(), 2u);

  for (const auto& sensor : scans.sensors) {
    std::vector<TimeNs> stamps;
    auto source = reader.open_scans(sensor.name);
    PointCloud cloud;
    while (source->next(cloud))
      if (cloud.t_ns >= truth.front().t_ns && cloud.t_ns <= truth.back().t_ns)
        stamps.push_back(cloud.t_ns);
    size_t expected_scans = 0;
    for (size_t j = 0; j < keyframes.size(); ++j) {
      TimeNs half = std::numeric_limits<TimeNs>::max();
      if (j > 0) half = std::min(half, (keyframes[j] - keyframes[j - 1]) / 2);
      if (j + 1 < keyframes.size()) half = std::min(half, (keyframes[j + 1] - keyframes[j]) / 2);
      TimeNs best = -1, best_dt = std::numeric_limits<TimeNs>::max();
      for (TimeNs t : stamps) {
        const TimeNs dt = std::abs(t - keyframes[j]);
        const bool nearer_other =  // a scan nearer another keyframe belongs to that one
            (j > 0 && std::abs(t - keyframes[j - 1]) < dt) ||
            (j + 1 < keyframes.size() && std::abs(t - keyframes[j + 1]) < dt);
        if (dt <= half && dt < best_dt && !nearer_other) best = t, best_dt = dt;
      }
      auto it = std::find_if(sensor.scans.begin(), sensor.scans.end(),
                             [&](const CalibrationScan& s) { return s.keyframe == j; });
      if (best < 0) {
        EXPECT_EQ(it, sensor.scans.end()) << sensor.name << " keyframe " << j;
        continue;
      }
      ++expected_scans;
      ASSERT_NE(it, sensor.scans.end()) << sensor.name << " keyframe " << j;
      EXPECT_NEAR(scans.t0_s + it->t_s, ns_to_seconds(best), 1e-6)
          << sensor.name << " keyframe " << j;
      EXPECT_FALSE(it->points.empty());
    }
    EXPECT_EQ(sensor.scans.size(), expected_scans) << sensor.name;
  }

  // Placed as Algorithm 3 places them, with the true poses and extrinsics, the vertical
  // lidar's points lie on what the horizontal one saw (keel-sim's range noise is 1 cm).
  std::vector<Eigen::Vector3d> reference;
  for (const auto& scan : scans.sensors[0].scans)
    for (const auto& p : scan.points)
      reference.push_back(scan.T_world_body * scans.sensors[0].T_body_sensor * p.cast<double>());
  std::vector<double> distances;
  for (size_t k = 0; k < scans.sensors[1].scans.size(); k += 2) {
    const auto& scan = scans.sensors[1].scans[k];
    for (size_t i = 0; i < scan.points.size(); i += 7) {
      const Eigen::Vector3d p =
          scan.T_world_body * scans.sensors[1].T_body_sensor * scan.points[i].cast<double>();
      double best = 1e9;
      for (const auto& q : reference) best = std::min(best, (p - q).squaredNorm());
      if (best < 0.5 * 0.5) distances.push_back(std::sqrt(best));
    }
  }
  ASSERT_GE(distances.size(), 50u) << "the two lidars should overlap in 12 s of the bridge";
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
  EXPECT_LT(distances[distances.size() / 2], 0.05);
}

}  // namespace
}  // namespace keel::pipeline
