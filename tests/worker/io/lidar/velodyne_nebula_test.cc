// Velodyne packets against an independent decoder's published output: nebula's decoder
// ground truth (github.com/tier4/nebula, nebula_velodyne/test_resources/decoder_ground_truth:
// rosbag2 .db3 bags of velodyne_msgs/msg/VelodyneScan and the clouds its decoder made of
// them). KEEL_NEBULA_TESTDATA names nebula's src/nebula_velodyne folder; without it the tests
// skip, saying so.
//
// nebula's test settings (nebula_tests/velodyne/velodyne_ros_decoder_test_{vlp16,vlp32}.cpp):
//   VLP-16: calibration VLP16.yaml, dual return, min_range 0.3 m, max_range 300 m,
//           cloud_min_angle 0, cloud_max_angle 359 deg, scan_phase 0; the cloud is one
//           rotation, from the 0 deg crossing in message 3 to message 4's last firing <= 359 deg.
//   VLP-32C: calibration VLP32.yaml, single (strongest) return, min_range 0.4 m, max_range
//           50 m, cloud_min_angle 270, cloud_max_angle 90 deg (blocks outside are dropped);
//           the cloud is message 1.
// Asserted: the same points in the same order (count, laser), each point's range and z within
// 1 mm, and each point within 1 mm once turned to the azimuth nebula assigns to its firing.
// nebula's azimuths differ from the manuals' per-firing interpolation (which Keel decodes,
// checked in closed form by velodyne_packet_test.cc): its VLP-16 decoder puts a dual
// packet's odd (second-return) blocks at the next firing group's azimuth and does not
// interpolate the packet's last group; its VLP-32 decoder spaces every laser 2.304 us (the
// VLP-32C fires pairs); neither interpolates a packet's last group; both round to 0.01 deg. Those
// azimuth models are written out below from the ground truth, and the plain (unturned) differences
// are printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "worker/io/bag/db3_reader.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/lidar/velodyne_scan.h"

namespace keel::io::lidar {
namespace {

namespace fs = std::filesystem;

fs::path testdata() {
  const char* env = std::getenv("KEEL_NEBULA_TESTDATA");
  return env ? fs::path(env) : fs::path();
}

uint16_t block_azimuth(const uint8_t* packet, size_t block) {
  return static_cast<uint16_t>(packet[block * 100 + 2] | (packet[block * 100 + 3] << 8));
}

// One decoded return with what the comparison needs to know about its firing.
struct Decoded {
  VelodynePoint point;
  int nebula_azimuth_cdeg = 0;  // the azimuth nebula's decoder gives this firing
  int nebula_block_azimuth_cdeg = 0;
  size_t message = 0;
};

// nebula's VLP-16 azimuth of a firing (dual return): block 0 at its own azimuth, blocks 1..9
// at the azimuth of block b + 1 (for an odd block: the next group), blocks 10 and 11 at block
// 11's; the rate from the block two ahead, none for blocks 10 and 11.
void nebula_vlp16_azimuth(const uint8_t* packet, Decoded& d) {
  const size_t b = d.point.block;
  const int own = b == 0 ? block_azimuth(packet, 0) : block_azimuth(packet, b >= 10 ? 11 : b + 1);
  const int step = b < 10 ? (36000 + block_azimuth(packet, b + 2) - own) % 36000 : 0;
  const double in_group_us = (d.point.time_s - (b / 2) * 110.592e-6) * 1e6;
  d.nebula_block_azimuth_cdeg = own;
  d.nebula_azimuth_cdeg = static_cast<int>(std::lround(own + step * in_group_us / 110.592)) % 36000;
}

// nebula's VLP-32 azimuth: the block's own, every laser 2.304 us after the previous at the
// rate to the next block (none in the packet's last block).
void nebula_vlp32_azimuth(const uint8_t* packet, Decoded& d) {
  const size_t b = d.point.block;
  const int own = block_azimuth(packet, b);
  const int step = b < 11 ? (36000 + block_azimuth(packet, b + 1) - own) % 36000 : 0;
  d.nebula_block_azimuth_cdeg = own;
  d.nebula_azimuth_cdeg =
      static_cast<int>(std::lround(own + step * d.point.laser * 2.304 / 55.296)) % 36000;
}

std::vector<Decoded> decode_bag(
    const fs::path& db3, const VelodyneCalibration& calibration,
    const VelodyneDecodeOptions& options,
    const std::function<void(const uint8_t*, Decoded&)>& nebula_azimuth) {
  Db3Reader reader(db3);
  EXPECT_EQ(reader.topics().size(), 1u);
  EXPECT_EQ(reader.topics()[0].type, "velodyne_msgs/msg/VelodyneScan");
  std::vector<Decoded> decoded;
  auto cursor = reader.messages(reader.topics()[0].id);
  Db3Message message;
  std::vector<VelodynePoint> points;
  for (size_t m = 0; cursor.next(message); ++m) {
    const VelodyneScanView scan = parse_velodyne_scan_cdr(message.data, message.size);
    for (const VelodynePacketView& packet : scan.packets) {
      points.clear();
      decode_velodyne_packet(packet.data, kVelodynePacketBytes, calibration, options, points);
      for (const VelodynePoint& p : points) {
        Decoded d{p, 0, 0, m};
        nebula_azimuth(packet.data, d);
        decoded.push_back(d);
      }
    }
  }
  return decoded;
}

// Compares in order; returns the largest plain (unturned) distance.
void compare(const std::vector<Decoded>& ours, const PointCloud& reference) {
  ASSERT_EQ(ours.size(), reference.size());
  double worst_plain = 0, worst_turned = 0;
  size_t failures = 0;
  for (size_t i = 0; i < ours.size(); ++i) {
    const VelodynePoint& p = ours[i].point;
    const Eigen::Vector3d ref = reference.xyz[i].cast<double>();
    const Eigen::Vector3d mine(p.x, p.y, p.z);
    worst_plain = std::max(worst_plain, (mine - ref).norm());
    // Turn to nebula's azimuth: alpha grows by delta, so (x, y) turns by -delta about z.
    const double delta = ours[i].nebula_azimuth_cdeg * M_PI / 18000.0 - p.azimuth_rad;
    const Eigen::Vector3d turned(mine.x() * std::cos(delta) + mine.y() * std::sin(delta),
                                 mine.y() * std::cos(delta) - mine.x() * std::sin(delta), mine.z());
    const double error = (turned - ref).norm();
    worst_turned = std::max(worst_turned, error);
    const bool ok = error < 1e-3 && std::abs(mine.norm() - ref.norm()) < 1e-3 &&
                    std::abs(mine.z() - ref.z()) < 1e-3;
    if (!ok && ++failures <= 10)
      ADD_FAILURE() << "point " << i << " (message " << ours[i].message << ", block "
                    << int(p.block) << ", laser " << int(p.laser) << "): ours turned "
                    << turned.transpose() << ", nebula " << ref.transpose();
  }
  EXPECT_EQ(failures, 0u);
  std::printf(
      "%zu points; largest distance to nebula's: %.6f m as decoded (per-firing "
      "azimuth), %.6f m at nebula's azimuth\n",
      ours.size(), worst_plain, worst_turned);
}

TEST(VelodyneNebula, Vlp16DualReturnCloud) {
  const fs::path root = testdata();
  if (root.empty())
    GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const fs::path truth = root / "nebula_velodyne/test_resources/decoder_ground_truth/vlp16";
  const auto calibration = load_velodyne_calibration(
      root / "nebula_velodyne_decoders/calibration/VLP16.yaml", VelodyneModel::kVlp16);
  VelodyneDecodeOptions options;
  options.min_range_m = 0.3;
  options.max_range_m = 300.0;
  const auto all = decode_bag(truth / "1673400471837873222/1673400471837873222_0.db3", calibration,
                              options, nebula_vlp16_azimuth);
  // The rotation: from the first 0 deg crossing in messages 3-4 (0-based 2-3) to the next;
  // nebula drops firings beyond 359 deg (cloud_max_angle) by its block and firing azimuths.
  std::vector<Decoded> rotation;
  int crossings = 0;
  int previous = -1;
  for (const Decoded& d : all) {
    if (d.message < 2) continue;
    if (previous >= 0 && d.nebula_azimuth_cdeg < previous - 18000) ++crossings;
    previous = d.nebula_azimuth_cdeg;
    if (crossings == 1 && d.nebula_azimuth_cdeg <= 35900 && d.nebula_block_azimuth_cdeg <= 35900)
      rotation.push_back(d);
  }
  const PointCloud reference = read_pcd(truth / "1673400472138016708.pcd", 0, {});
  compare(rotation, reference);
}

TEST(VelodyneNebula, Vlp32StrongestReturnCloud) {
  const fs::path root = testdata();
  if (root.empty())
    GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const fs::path truth = root / "nebula_velodyne/test_resources/decoder_ground_truth/vlp32";
  const auto calibration = load_velodyne_calibration(
      root / "nebula_velodyne_decoders/calibration/VLP32.yaml", VelodyneModel::kVlp32c);
  VelodyneDecodeOptions options;
  options.min_range_m = 0.4;
  options.max_range_m = 50.0;
  const auto all = decode_bag(truth / "1713492677464078412/1713492677464078412_0.db3", calibration,
                              options, nebula_vlp32_azimuth);
  std::vector<Decoded> first;
  for (const Decoded& d : all) {
    const int block = d.point.block_azimuth_cdeg;
    if (d.message == 0 && (block <= 9000 || block >= 27000)) first.push_back(d);
  }
  const PointCloud reference = read_pcd(truth / "1713492677464078412.pcd", 0, {});
  compare(first, reference);
}

TEST(VelodyneNebula, FactoryTablesEqualTheDriversCalibration) {
  const fs::path root = testdata();
  if (root.empty())
    GTEST_SKIP() << "KEEL_NEBULA_TESTDATA is not set (nebula's src/nebula_velodyne)";
  const std::pair<VelodyneModel, const char*> files[] = {{VelodyneModel::kVlp16, "VLP16.yaml"},
                                                         {VelodyneModel::kVlp32c, "VLP32.yaml"},
                                                         {VelodyneModel::kHdl32e, "HDL32.yaml"}};
  for (const auto& [model, file] : files) {
    SCOPED_TRACE(file);
    const auto yaml =
        load_velodyne_calibration(root / "nebula_velodyne_decoders/calibration" / file, model);
    const auto factory = factory_calibration(model);
    EXPECT_DOUBLE_EQ(yaml.distance_resolution_m, factory.distance_resolution_m);
    for (size_t i = 0; i < factory.lasers.size(); ++i) {
      // The drivers' files hold the manuals' degrees in radians to ~1e-3 deg.
      EXPECT_NEAR(yaml.lasers[i].vert_rad, factory.lasers[i].vert_rad, 2e-5) << i;
      EXPECT_NEAR(yaml.lasers[i].rot_rad, factory.lasers[i].rot_rad, 2e-5) << i;
      EXPECT_EQ(yaml.lasers[i].ring, factory.lasers[i].ring) << i;
    }
  }
}

}  // namespace
}  // namespace keel::io::lidar
