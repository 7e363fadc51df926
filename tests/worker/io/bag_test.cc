#include "worker/io/bag/bag_reader.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "io_test_util.h"
#include "worker/io/io_error.h"
#include "worker/io/mission_reader.h"

namespace keel::io {
namespace {

using testing::expect_error;
using testing::TempDir;
using testing::write_text;

constexpr TimeNs kT0 = 1700000000LL * 1000000000LL;

// Writes the test bag with Debian's python (python3-rosbag), its chunks stored as they are or
// compressed ("lz4", "bz2"); empty path when it cannot.
std::filesystem::path make_bag(const TempDir& dir, const std::string& compression = "none") {
  const auto bag = dir / "mission.bag";
  const std::string command = std::string("/usr/bin/python3 ") + KEEL_SOURCE_DIR +
                              "/tests/worker/io/make_test_bag.py " + bag.string() + " " +
                              compression;
  if (std::system(command.c_str()) != 0) return {};
  return bag;
}

#define MAKE_BAG_OR_SKIP(dir, bag) \
  const auto bag = make_bag(dir);  \
  if (bag.empty()) GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag unavailable"

TEST(Bag, ListsTopicsWithTypesAndCounts) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  BagReader reader(bag);
  EXPECT_EQ(reader.topics().size(), 9u);
  EXPECT_EQ(reader.topic("/imu/data").datatype, "sensor_msgs/Imu");
  EXPECT_EQ(reader.topic("/imu/data").messages, 200u);
  EXPECT_EQ(reader.topic("/lidar/points").messages, 5u);
}

// Each compression rosbag writes (Keel decompresses the chunks to check their records first).
class BagCompressions : public ::testing::TestWithParam<std::string> {};
INSTANTIATE_TEST_SUITE_P(Bag, BagCompressions, ::testing::Values("none", "lz4", "bz2"));

TEST_P(BagCompressions, ImuDvlAndTrajectoriesFollowTheirClosedForms) {
  TempDir dir;
  const auto bag = make_bag(dir, GetParam());
  if (bag.empty()) GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag unavailable";
  BagReader reader(bag);
  const ImuSeries imu = reader.read_imu("/imu/data");
  ASSERT_EQ(imu.size(), 200u);
  for (size_t i = 0; i < imu.size(); i += 37) {
    EXPECT_EQ(imu[i].t_ns, kT0 + static_cast<TimeNs>(i) * 5000000);
    EXPECT_DOUBLE_EQ(imu[i].gyro_rad_s.x(), 0.01 * i);
    EXPECT_DOUBLE_EQ(imu[i].accel_m_s2.z(), 9.81);
  }
  const DvlSeries dvl = reader.read_dvl("/dvl/twist");
  ASSERT_EQ(dvl.size(), 20u);
  EXPECT_DOUBLE_EQ(dvl[7].velocity_m_s.y(), 0.7000000000000001);
  EXPECT_EQ(dvl[7].t_ns, kT0 + 7 * 50000000LL);
  const DvlSeries plain = reader.read_dvl("/dvl/twist_plain");
  ASSERT_EQ(plain.size(), 5u);
  EXPECT_EQ(plain[4].velocity_m_s.x(), 0.5);
  const Trajectory odom = reader.read_trajectory("/slam/odom");
  ASSERT_EQ(odom.size(), 10u);
  EXPECT_EQ(odom[3].T_world_body.translation(), Eigen::Vector3d(3, 0, 0));
  const double yaw = Eigen::AngleAxisd(odom[3].T_world_body.linear()).angle();
  EXPECT_NEAR(yaw, 0.3, 1e-12);
  const Trajectory keyframes = reader.read_trajectory("/slam/keyframes");
  ASSERT_EQ(keyframes.size(), 3u);
  EXPECT_EQ(keyframes[2].t_ns, kT0 + 2000000000LL);
  EXPECT_EQ(keyframes[2].T_world_body.translation().y(), 2.0);
  expect_error(
      [&] { reader.read_imu("/slam/odom"); },
      {"mission.bag", "topic '/slam/odom' holds nav_msgs/Odometry", "expected sensor_msgs/Imu"});
}

TEST(Bag, PointCloudsStreamWithOusterNanosecondTimes) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  BagReader reader(bag);
  ScanReadOptions options;
  options.point_time =
      proto::PointTimeSpec{"t", proto::TimeUnit::kNanoseconds, proto::TimeReference::kScanStart};
  options.sweep_period_s = 0.1;
  auto scans = reader.open_scans("/lidar/points", options);
  ASSERT_EQ(scans->size(), 5u);
  PointCloud cloud;
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(scans->next(cloud));
    ASSERT_EQ(cloud.size(), 100u);
    EXPECT_EQ(cloud.t_ns, kT0 + k * 100000000LL);
    EXPECT_FLOAT_EQ(cloud.xyz[42].x(), static_cast<float>(0.01 * 42 + k));
    EXPECT_EQ(cloud.xyz[42].y(), static_cast<float>(k));
    EXPECT_EQ(cloud.intensity[42], 42.0f);
    EXPECT_EQ(cloud.ring[42], 42 % 16);
    EXPECT_FLOAT_EQ(cloud.time_s[42], 0.042f);
  }
  EXPECT_FALSE(scans->next(cloud));
  // The same field declared as seconds is impossible for a 10 Hz sweep.
  options.point_time->unit = proto::TimeUnit::kSeconds;
  auto wrong = reader.open_scans("/lidar/points", options);
  expect_error([&] { wrong->next(cloud); },
               {"mission.bag: topic '/lidar/points' message 0", "field 't'", "fit unit ns"});
}

TEST(Bag, ImagesRawAndCompressed) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  BagReader reader(bag);
  auto images = reader.open_images("/cam/image");
  ImageFrame f;
  ASSERT_TRUE(images->next(f, true));
  ASSERT_TRUE(images->next(f, true));
  EXPECT_EQ(f.t_ns, kT0 + 50000000LL);
  EXPECT_EQ(f.width, 4);
  EXPECT_EQ(f.height, 3);
  EXPECT_EQ(f.channels, 3);
  // Pixel (r=2, c=3) was written as bgr (3, 2, 10): RGB order is (10, 2, 3).
  const size_t at = (2 * 4 + 3) * 3;
  EXPECT_EQ(f.pixels[at + 0], 10);
  EXPECT_EQ(f.pixels[at + 1], 2);
  EXPECT_EQ(f.pixels[at + 2], 3);
  auto compressed = reader.open_images("/cam/compressed");
  ASSERT_EQ(compressed->size(), 2u);
  ASSERT_TRUE(compressed->next(f, true));
  ASSERT_TRUE(compressed->next(f, true));
  EXPECT_EQ(f.width, 5);
  EXPECT_EQ(f.height, 2);
  EXPECT_EQ(f.channels, 1);
  EXPECT_EQ(f.pixels[9], 7);
}

TEST(Bag, StaticTransformsChainToTheBodyFrame) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  BagReader reader(bag);
  const auto tf = reader.read_static_transforms();
  ASSERT_EQ(tf.size(), 2u);
  Pose3 T;
  ASSERT_TRUE(lookup_static_transform(tf, "base_link", "lidar_optical", T));
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(0.1, 0, 0.5), 1e-12));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  ASSERT_TRUE(lookup_static_transform(tf, "lidar_optical", "base_link", T));
  EXPECT_TRUE((T * Eigen::Vector3d(0.1, 0, 0.5)).isZero(1e-12));
  EXPECT_FALSE(lookup_static_transform(tf, "base_link", "camera", T));
}

TEST(Bag, MissingTopicNamesTopicAndTheBagsTopics) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  BagReader reader(bag);
  expect_error(
      [&] { reader.read_imu("/imu/raw"); },
      {"mission.bag", "no topic '/imu/raw'", "/imu/data (sensor_msgs/Imu)", "/lidar/points"});
}

TEST(Bag, TruncatedBagIsNamed) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  std::filesystem::resize_file(bag, std::filesystem::file_size(bag) / 2);
  expect_error([&] { BagReader reader(bag); }, {"mission.bag", "truncated or corrupt"});
}

// A header field longer than its header: rosbag's ros::Header::parse read past its buffer
// (heap-buffer-overflow, found by fuzz_bag); refused before rosbag reads the file.
TEST(Bag, HeaderFieldLongerThanItsHeaderIsRefused) {
  TempDir dir;
  auto le32 = [](uint32_t v) {
    return std::string{char(v & 0xff), char(v >> 8 & 0xff), char(v >> 16 & 0xff), char(v >> 24)};
  };
  const std::string op = std::string("op=") + char(0x03);
  std::ofstream(dir / "long.bag", std::ios::binary) << "#ROSBAG V2.0\n"
                                                    << le32(4 + 4) << le32(200) << op << le32(0);
  expect_error([&] { BagReader reader(dir / "long.bag"); },
               {"long.bag", "truncated or corrupt", "record at byte 13", "runs past its header"});
  std::ofstream(dir / "noeq.bag", std::ios::binary) << "#ROSBAG V2.0\n"
                                                    << le32(4 + 4) << le32(4) << "op:x" << le32(0);
  expect_error([&] { BagReader reader(dir / "noeq.bag"); }, {"noeq.bag", "no '='"});
}

// A connection whose MD5 is not its type's (a corrupt connection record, or a message
// definition changed under the same type name): rosbag hands back no message, which fuzz_bag
// found dereferenced; the error names the bag, topic, message and both MD5s.
TEST(Bag, MessageWhoseMd5IsNotItsTypesIsNamed) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  std::ifstream in(bag, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const std::string pose_md5 = "d3812c3cbc69362b77dc0b19b345f8f5";  // geometry_msgs/PoseStamped
  const std::string other_md5(32, 'a');
  size_t replaced = 0;
  for (size_t at = bytes.find(pose_md5); at != std::string::npos; at = bytes.find(pose_md5, at)) {
    bytes.replace(at, pose_md5.size(), other_md5);
    ++replaced;
  }
  ASSERT_GT(replaced, 0u);
  std::ofstream(bag, std::ios::binary | std::ios::trunc) << bytes;
  BagReader reader(bag);
  expect_error([&] { (void)reader.read_trajectory("/slam/keyframes"); },
               {"mission.bag", "topic '/slam/keyframes' message 0",
                "a geometry_msgs/PoseStamped message (MD5 " + other_md5 + ")",
                "not a geometry_msgs/PoseStamped (MD5 " + pose_md5 + ")"});
}

// The top-level records of a bag 2.0 file: where each header field's value and each
// record's data start, to corrupt one in place.
struct BagRecord {
  int op = -1;
  size_t at = 0, data_at = 0;
  std::map<std::string, size_t> value_at;  // field name -> byte of its value
};
std::vector<BagRecord> bag_records(const std::string& bytes) {
  auto le32 = [&](size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  std::vector<BagRecord> out;
  for (size_t at = 13; at + 8 <= bytes.size();) {
    BagRecord r;
    r.at = at;
    const uint32_t header_length = le32(at);
    for (size_t f = at + 4; f < at + 4 + header_length;) {
      const uint32_t length = le32(f);
      const std::string field = bytes.substr(f + 4, length);
      const std::string name = field.substr(0, field.find('='));
      r.value_at[name] = f + 4 + name.size() + 1;
      if (name == "op") r.op = static_cast<unsigned char>(field[name.size() + 1]);
      f += 4 + length;
    }
    r.data_at = at + 8 + header_length;
    out.push_back(r);
    at = r.data_at + le32(at + 4 + header_length);
  }
  return out;
}

void put_le32(std::string& bytes, size_t at, uint32_t v) { std::memcpy(bytes.data() + at, &v, 4); }

// rosbag reads a record wherever the bag's own positions point: an index entry (its offset
// in the chunk), a chunk info (chunk_pos) and the bag header (index_pos) must each point at a
// record, and a chunk must be as long as its `size` says once uncompressed. fuzz_bag's lz4
// chunk whose index entry pointed 2.7 GB away read rosbag out of bounds (SEGV).
TEST_P(BagCompressions, PositionsThatPointAtNoRecordAreRefused) {
  TempDir dir;
  const auto bag = make_bag(dir, GetParam());
  if (bag.empty()) GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag unavailable";
  std::ifstream in(bag, std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const std::vector<BagRecord> records = bag_records(good);
  const auto first = [&](int op) {
    for (const BagRecord& r : records)
      if (r.op == op) return r;
    ADD_FAILURE() << "no record of op " << op;
    return BagRecord{};
  };
  const auto refused = [&](const std::string& bytes, const std::vector<std::string>& needles) {
    std::ofstream(bag, std::ios::binary | std::ios::trunc) << bytes;
    try {
      BagReader reader(bag);
      ADD_FAILURE() << "accepted; expected: " << needles.back();
    } catch (const IoError& e) {
      for (const std::string& needle : needles)
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
            << "'" << needle << "' not in: " << e.what();
    }
  };
  std::string bytes = good;
  const BagRecord index = first(0x04);
  put_le32(bytes, index.data_at + 8, 2779096209u);  // entry 0: uint64 time, uint32 offset
  refused(bytes, {"mission.bag", "record at byte " + std::to_string(index.at),
                  "index entry 0 points at byte 2779096209 of its chunk, where no record starts"});

  bytes = good;
  const BagRecord chunk = first(0x05);
  put_le32(bytes, chunk.value_at.at("size"), 1234567);
  refused(bytes, {"record at byte " + std::to_string(chunk.at), "'size' field says 1234567"});

  bytes = good;
  const BagRecord info = first(0x06);
  put_le32(bytes, info.value_at.at("chunk_pos"), 13);  // the bag header: a record, not a chunk
  refused(bytes, {"chunk_pos 13 is not the start of a chunk"});

  bytes = good;
  put_le32(bytes, first(0x03).value_at.at("index_pos"), static_cast<uint32_t>(chunk.at + 1));
  refused(bytes, {"index_pos " + std::to_string(chunk.at + 1) + " is not the start of a record"});
  // A connection record's data is the publisher's connection header, parsed by
  // ros::Header::parse as trustingly (fuzz_bag: heap-buffer-overflow): its first field's length.
  bytes = good;
  BagRecord connection;
  for (const BagRecord& r : records)
    if (r.op == 0x07) connection = r;  // the last: in the index section, after the chunks
  put_le32(bytes, connection.data_at, 16473);
  refused(bytes, {"record at byte " + std::to_string(connection.at) + " (its connection header)",
                  "a header field of 16473 bytes runs past its header"});
  std::ofstream(bag, std::ios::binary | std::ios::trunc) << good;
  EXPECT_NO_THROW(BagReader reader(bag));
}

std::string bag_mission_yaml(const std::string& imu_topic) {
  return "keel_mission: 1\nname: bag-mission\nbag: mission.bag\nsensors:\n"
         "  - {name: imu, type: imu, topic: " +
         imu_topic +
         ", rate_hz: 200}\n"
         "  - {name: dvl, type: dvl, topic: /dvl/twist, rate_hz: 20}\n"
         "  - name: lidar\n    type: lidar\n    topic: /lidar/points\n    rate_hz: 10\n"
         "    point_time: {field: t, unit: ns}\n"
         "  - {name: optical, type: camera, topic: /cam/image, frame_id: lidar_optical, rate_hz: "
         "20,\n"
         "     camera: {model: pinhole, width: 4, height: 3, fx: 2, fy: 2, cx: 2, cy: 1.5}}\n"
         "trajectories:\n  odometry: {topic: /slam/odom}\n  map: {topic: /slam/keyframes}\n";
}

TEST(Bag, MissionReaderGivesTheSameTypesFromABag) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  write_text(dir / "mission.yaml", bag_mission_yaml("/imu/data"));
  MissionReader reader(load_mission(dir.path()));
  EXPECT_EQ(reader.read_imu("imu").size(), 200u);
  EXPECT_EQ(reader.read_dvl("dvl").size(), 20u);
  EXPECT_EQ(reader.read_trajectory("odometry").size(), 10u);
  EXPECT_EQ(reader.read_trajectory("map").size(), 3u);
  auto scans = reader.open_scans("lidar");
  PointCloud cloud;
  ASSERT_TRUE(scans->next(cloud));
  EXPECT_EQ(cloud.frame, "lidar");
  EXPECT_FLOAT_EQ(cloud.time_s[99], 0.099f);
  const auto T_body_lidar = reader.extrinsic("lidar");
  ASSERT_TRUE(T_body_lidar);
  EXPECT_TRUE(T_body_lidar->translation().isApprox(Eigen::Vector3d(0, 0, 0.5)));
  const auto T_body_optical = reader.extrinsic("optical");
  ASSERT_TRUE(T_body_optical);
  EXPECT_TRUE(T_body_optical->translation().isApprox(Eigen::Vector3d(0.1, 0, 0.5), 1e-12));
  EXPECT_FALSE(reader.extrinsic("imu"));
}

TEST(Bag, MissionWithMissingTopicNamesFieldAndTopics) {
  TempDir dir;
  MAKE_BAG_OR_SKIP(dir, bag);
  write_text(dir / "mission.yaml", bag_mission_yaml("/imu/raw"));
  expect_error([&] { MissionReader reader(load_mission(dir.path())); },
               {"mission.yaml: sensors[0].topic", "no topic '/imu/raw'", "/imu/data"});
}

}  // namespace
}  // namespace keel::io
