// A bag topic of velodyne_msgs/VelodyneScan opens as scans (BagSource::open_scans), one per
// message, each point with its firing time; the ROS 2 reader on nebula's rosbag2 test bag and
// the ROS 1 reader on the same messages re-recorded (velodyne_ros1_bag.py) give the same
// scans. Needs KEEL_NEBULA_TESTDATA (nebula's src/nebula_velodyne); skips without it.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "worker/io/bag/bag_source.h"
#include "worker/io/io_error.h"
#include "worker/io/lidar/velodyne_calibration.h"
#include "worker/io/mission.h"
#include "worker/io/mission_reader.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;

fs::path vlp16_bag() {
  const char* env = std::getenv("KEEL_NEBULA_TESTDATA");
  if (!env) return {};
  return fs::path(env) /
         "nebula_velodyne/test_resources/decoder_ground_truth/vlp16/1673400471837873222";
}

ScanReadOptions packet_options() {
  ScanReadOptions options;
  options.frame = "lidar";
  options.packets = std::make_shared<const lidar::VelodyneCalibration>(
      lidar::factory_calibration(lidar::VelodyneModel::kVlp16));
  return options;
}

std::vector<PointCloud> read_all(const fs::path& bag) {
  auto source = open_bag(bag)->open_scans("/velodyne_packets", packet_options());
  EXPECT_EQ(source->size(), 4u);
  std::vector<PointCloud> scans;
  PointCloud cloud;
  while (source->next(cloud)) scans.push_back(cloud);
  return scans;
}

TEST(VelodyneBag, Ros2TopicGivesOneTimedScanPerMessage) {
  const fs::path bag = vlp16_bag();
  if (bag.empty()) GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const auto scans = read_all(bag);
  ASSERT_EQ(scans.size(), 4u);
  // First packet stamps of the four messages (read from the bag with sqlite3 and struct).
  const TimeNs first_packet_ns[4] = {1673400471737763166, 1673400471837960720, 1673400471938157320,
                                     1673400472038354158};
  for (size_t i = 0; i < scans.size(); ++i) {
    SCOPED_TRACE(i);
    const PointCloud& scan = scans[i];
    EXPECT_EQ(scan.t_ns, first_packet_ns[i]);
    EXPECT_EQ(scan.frame, "lidar");
    ASSERT_TRUE(scan.has_time());
    ASSERT_TRUE(scan.has_ring());
    // One rotation of this indoor scene: nebula's cloud of it holds 14831 returns beyond
    // 0.3 m (decoded here without a range limit); at most 150 packets x 384 slots.
    EXPECT_NEAR(static_cast<double>(scan.size()), 14831.0, 300.0);
    EXPECT_LE(scan.size(), 151u * 384u);
    float first = 1e9f, last = -1e9f;
    for (float t : scan.time_s) first = std::min(first, t), last = std::max(last, t);
    EXPECT_GE(first, 0.0f);
    EXPECT_LT(first, 3e-6f);  // the first firing with a return
    // The sensor clock says each message spans 150 packets of 1327.104 us (24 sequences of
    // 55.296 us): the last firing is at most one packet after the last packet's start.
    EXPECT_GT(last, 0.098f);
    EXPECT_LT(last, 0.1005f);
    for (uint16_t ring : scan.ring) EXPECT_LT(ring, 16);
  }
  // Consecutive sweeps start one rotation (0.1 s at 600 rpm) apart.
  for (size_t i = 1; i < scans.size(); ++i)
    EXPECT_NEAR((scans[i].t_ns - scans[i - 1].t_ns) * 1e-9, 0.1, 0.002);
}

TEST(VelodyneBag, Ros1AndRos2ReadersAgree) {
  const fs::path bag = vlp16_bag();
  if (bag.empty()) GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const fs::path ros1 =
      fs::temp_directory_path() / ("keel-velodyne-" + std::to_string(getpid()) + ".bag");
  const std::string command = std::string("/usr/bin/python3 ") + KEEL_SOURCE_DIR +
                              "/tests/worker/io/lidar/velodyne_ros1_bag.py " +
                              (bag / "1673400471837873222_0.db3").string() + " " + ros1.string();
  if (std::system(command.c_str()) != 0)
    GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag unavailable";
  const auto a = read_all(bag);
  const auto b = read_all(ros1);
  fs::remove(ros1);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    ASSERT_EQ(a[i].size(), b[i].size());
    for (size_t k = 0; k < a[i].size(); ++k) {
      ASSERT_EQ(a[i].xyz[k], b[i].xyz[k]);
      ASSERT_EQ(a[i].time_s[k], b[i].time_s[k]);
    }
  }
}

TEST(VelodyneBag, PacketTopicWithoutPacketsSaysWhatToWrite) {
  const fs::path bag = vlp16_bag();
  if (bag.empty()) GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  try {
    open_bag(bag)->open_scans("/velodyne_packets", {});
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("topic '/velodyne_packets' holds raw Velodyne packets"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("packets: {model:"), std::string::npos) << e.what();
  }
}

TEST(VelodyneBag, WrongModelIsAnErrorNamingTopicMessageAndPacket) {
  const fs::path bag = vlp16_bag();
  if (bag.empty()) GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  ScanReadOptions options = packet_options();
  options.packets = std::make_shared<const lidar::VelodyneCalibration>(
      lidar::factory_calibration(lidar::VelodyneModel::kHdl32e));
  auto source = open_bag(bag)->open_scans("/velodyne_packets", options);
  PointCloud cloud;
  try {
    source->next(cloud);
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "topic '/velodyne_packets' message 0 packet 0: product id byte 0x22 is not a "
                  "HDL32E (0x21)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace keel::io

namespace keel::io {
namespace {

// A bundle whose lidar is the nebula bag's packet topic, with or without a calibration file.
fs::path write_bundle(const fs::path& dir, const std::string& packets) {
  fs::create_directories(dir);
  fs::copy_file(vlp16_bag() / "1673400471837873222_0.db3", dir / "lidar.db3",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "mission.yaml")
      << "keel_mission: 1\nname: velodyne\nbag: lidar.db3\nsensors:\n"
         "  - name: lidar\n    type: lidar\n"
         "    topic: /velodyne_packets\n    rate_hz: 10\n"
         "    packets: "
      << packets << "\n";
  return dir;
}

TEST(VelodyneBag, MissionLidarWithPacketsAndCalibration) {
  if (vlp16_bag().empty())
    GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const fs::path dir =
      fs::temp_directory_path() / ("keel-velodyne-mission-" + std::to_string(getpid()));
  write_bundle(dir, "{model: VLP16, calibration: VLP16.yaml}");
  fs::copy_file(fs::path(std::getenv("KEEL_NEBULA_TESTDATA")) /
                    "nebula_velodyne_decoders/calibration/VLP16.yaml",
                dir / "VLP16.yaml", fs::copy_options::overwrite_existing);
  MissionReader reader(load_mission(dir));
  auto scans = reader.open_scans("lidar");
  PointCloud cloud;
  size_t count = 0;
  while (scans->next(cloud)) {
    EXPECT_EQ(cloud.frame, "lidar");
    EXPECT_TRUE(cloud.has_time());
    ++count;
  }
  EXPECT_EQ(count, 4u);

  // Without the file: an error naming the field.
  fs::remove(dir / "VLP16.yaml");
  try {
    load_mission(dir);
    ADD_FAILURE() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("sensors[0].packets.calibration: 'VLP16.yaml' not found"),
              std::string::npos)
        << e.what();
  }
  // A model Keel does not know: an error naming the field and the known ones.
  write_bundle(dir, "{model: HDL64E}");
  try {
    MissionReader(load_mission(dir)).open_scans("lidar");
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("packets"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("VLP16, VLP32C, HDL32E"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::io
