// ROS 2 bags: the container readers against rosbag2's own test bags (their metadata.yaml
// counts and the payloads rosbag2's tests assert), and every damaged-file error naming the
// file, the topic and the message index.
//
// rosbag2's test bags are fetched outside the project (never committed): point
// KEEL_ROSBAG2_TESTDATA (environment, or the CMake cache variable of the same name) at a
// folder holding rosbag2_tests/resources and rosbag2_py/test/resources of ros2/rosbag2.
// Those tests skip, saying so, when it is not set.
#include "worker/io/bag/rosbag2_reader.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>

#include "io_test_util.h"
#include "tests/sim/cdr_writer.h"
#include "tests/sim/db3_writer.h"
#include "tests/sim/mcap_writer.h"
#include "worker/io/bag/cdr_reader.h"
#include "worker/io/bag/crc32.h"
#include "worker/io/io_error.h"
#include "worker/io/bag/rosbag2_metadata.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;
using testing::expect_error;
using testing::TempDir;

fs::path testdata() {
  if (const char* env = std::getenv("KEEL_ROSBAG2_TESTDATA")) return env;
  return KEEL_ROSBAG2_TESTDATA;
}

#define REQUIRE_TESTDATA(rel)                                                     \
  const fs::path bag_dir = testdata() / rel;                                      \
  if (testdata().empty() || !fs::exists(bag_dir))                                 \
  GTEST_SKIP() << "rosbag2 test bags not found (" << bag_dir                      \
               << "): set KEEL_ROSBAG2_TESTDATA to a folder with ros2/rosbag2's " \
                  "rosbag2_tests/resources and rosbag2_py/test/resources"

// Every topic and count rosbag2 wrote into metadata.yaml equals what the storage files hold.
void expect_counts_match_metadata(const fs::path& bag_dir) {
  const Rosbag2Metadata metadata = read_rosbag2_metadata(bag_dir / "metadata.yaml");
  const Rosbag2Reader reader(bag_dir);
  EXPECT_EQ(reader.files().size(), metadata.relative_file_paths.size());
  EXPECT_EQ(reader.topics().size(), metadata.topics.size()) << bag_dir;
  uint64_t total = 0;
  for (const auto& t : metadata.topics) {
    ASSERT_TRUE(reader.has_topic(t.name)) << bag_dir << " " << t.name;
    const BagTopicInfo& info = reader.topic(t.name);
    EXPECT_EQ(info.messages, t.message_count) << bag_dir << " " << t.name;
    EXPECT_EQ(info.datatype, t.type) << bag_dir << " " << t.name;
    size_t read = 0;
    reader.for_each_message(t.name, [&](const Rosbag2Reader::RawMessage& m, size_t index) {
      EXPECT_EQ(index, read++);
      EXPECT_EQ(m.type, t.type);
    });
    EXPECT_EQ(read, t.message_count) << bag_dir << " " << t.name;
    total += read;
  }
  EXPECT_EQ(total, metadata.message_count) << bag_dir;
}

TEST(Rosbag2TestBags, CountsMatchTheirMetadataInBothStoragesAndSplitBags) {
  REQUIRE_TESTDATA("rosbag2_py/test/resources");
  for (const char* storage : {"mcap", "sqlite3"}) {
    for (const char* bag : {"talker", "wbag", "convert_a", "convert_b"})
      expect_counts_match_metadata(bag_dir / storage / bag);
  }
  for (const char* storage : {"mcap", "sqlite3"})
    for (const char* bag : {"cdr_test", "bag_with_topics_and_service_events"})
      expect_counts_match_metadata(testdata() / "rosbag2_tests/resources" / storage / bag);
}

// rosbag2_py's test_sequential_reader: /topic carries std_msgs/msg/String "Hello, world! <i>".
TEST(Rosbag2TestBags, TalkerStringsDecodeInRecordingOrder) {
  REQUIRE_TESTDATA("rosbag2_py/test/resources");
  for (const char* storage : {"mcap", "sqlite3"}) {
    const Rosbag2Reader reader(bag_dir / storage / "talker");
    TimeNs previous = 0;
    reader.for_each_message("/topic", [&](const Rosbag2Reader::RawMessage& m, size_t i) {
      CdrReader cdr(m.data, m.size);
      EXPECT_EQ(cdr.string("data"), "Hello, world! " + std::to_string(i)) << storage;
      EXPECT_GT(m.log_time_ns, previous);
      previous = m.log_time_ns;
    });
  }
}

// rosbag2_tests' play test: test_msgs/msg/BasicTypes int32_value 123, Arrays bool_values
// [true, false, true].
TEST(Rosbag2TestBags, CdrTestValuesDecode) {
  REQUIRE_TESTDATA("rosbag2_tests/resources");
  for (const char* storage : {"mcap", "sqlite3"}) {
    const Rosbag2Reader reader(bag_dir / storage / "cdr_test");
    size_t basic = 0, arrays = 0;
    reader.for_each_message("/test_topic", [&](const Rosbag2Reader::RawMessage& m, size_t) {
      CdrReader cdr(m.data, m.size);
      cdr.boolean("bool_value"), cdr.u8("byte_value"), cdr.u8("char_value");
      cdr.f32("float32_value"), cdr.f64("float64_value");
      cdr.u8("int8_value"), cdr.u8("uint8_value"), cdr.u16("int16_value"), cdr.u16("uint16_value");
      EXPECT_EQ(cdr.i32("int32_value"), 123) << storage;
      ++basic;
    });
    reader.for_each_message("/array_topic", [&](const Rosbag2Reader::RawMessage& m, size_t) {
      CdrReader cdr(m.data, m.size);
      EXPECT_TRUE(cdr.boolean("bool_values[0]"));
      EXPECT_FALSE(cdr.boolean("bool_values[1]"));
      EXPECT_TRUE(cdr.boolean("bool_values[2]"));
      ++arrays;
    });
    EXPECT_EQ(basic, 3u);
    EXPECT_EQ(arrays, 4u);
  }
}

// Files recorded without metadata.yaml (rosbag2's reindex tests) open one by one.
TEST(Rosbag2TestBags, LoneFilesOpenWithoutMetadata) {
  REQUIRE_TESTDATA("rosbag2_py/test/resources");
  for (const char* storage : {"mcap", "sqlite3"}) {
    const char* ext = std::string(storage) == "mcap" ? ".mcap" : ".db3";
    uint64_t total = 0;
    for (int i = 0; i < 3; ++i) {
      const fs::path file = bag_dir / storage / "reindex_test_bags/multiple_files" /
                            ("multiple_files_" + std::to_string(i) + ext);
      const Rosbag2Reader reader(file);
      for (const auto& t : reader.topics()) {
        size_t n = 0;
        reader.for_each_message(t.topic, [&](const Rosbag2Reader::RawMessage&, size_t) { ++n; });
        EXPECT_EQ(n, t.messages) << file << " " << t.topic;
        total += n;
      }
    }
    EXPECT_GT(total, 0u) << storage;
  }
}

// rosbag2's wrong_rmw_test bags declare serialization "wrong_format": refused per message.
TEST(Rosbag2TestBags, NonCdrSerializationIsRefusedNamingTopicAndMessage) {
  REQUIRE_TESTDATA("rosbag2_tests/resources");
  for (const char* storage : {"sqlite3"}) {
    const Rosbag2Reader reader(bag_dir / storage / "wrong_rmw_test");
    expect_error([&] { reader.for_each_message("/test_topic", [](const auto&, size_t) {}); },
                 {"wrong_rmw_test_0.db3: topic '/test_topic' message 0", "wrong_format", "cdr"});
  }
}

TEST(Crc32, CheckValueOfTheStandard) {
  const char* text = "123456789";  // the CRC-32/ISO-HDLC check value
  EXPECT_EQ(crc32(reinterpret_cast<const uint8_t*>(text), 9), 0xCBF43926u);
  // Incremental equals one pass, across the 8-byte blocks.
  uint32_t c = crc32(reinterpret_cast<const uint8_t*>(text), 5);
  EXPECT_EQ(crc32(reinterpret_cast<const uint8_t*>(text) + 5, 4, c), 0xCBF43926u);
}

// ---- damaged files, written here with keel-sim's writers ----

std::vector<uint8_t> imu_cdr(TimeNs t_ns, double gyro_x) {
  sim::CdrWriter w;
  w.i32(static_cast<int32_t>(t_ns / 1000000000));
  w.u32(static_cast<uint32_t>(t_ns % 1000000000));
  w.string("imu");
  for (int i = 0; i < 4 + 9; ++i) w.f64(i == 3 ? 1.0 : 0.0);
  w.f64(gyro_x), w.f64(0), w.f64(0);
  for (int i = 0; i < 9; ++i) w.f64(0);
  w.f64(0), w.f64(0), w.f64(9.81);
  for (int i = 0; i < 9; ++i) w.f64(0);
  return w.take();
}

constexpr TimeNs kT0 = 1700000000000000000LL;

// An MCAP with /imu (sensor_msgs/msg/Imu) and /chatter (std_msgs/msg/String), `n` each.
void write_mcap(const fs::path& path, const std::string& compression, int n,
                uint64_t chunk_bytes = 4096) {
  sim::McapWriter w(path.string(), {compression, chunk_bytes});
  const uint16_t imu = w.add_channel("/imu", w.add_schema("sensor_msgs/msg/Imu", "ros2msg", ""));
  const uint16_t chatter =
      w.add_channel("/chatter", w.add_schema("std_msgs/msg/String", "ros2msg", ""));
  for (int i = 0; i < n; ++i) {
    const TimeNs t = kT0 + i * 5000000LL;
    w.write(imu, t, imu_cdr(t, 0.001 * i));
    sim::CdrWriter s;
    s.string("hello " + std::to_string(i));
    w.write(chatter, t, s.take());
  }
  w.close();
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(Rosbag2Reader, McapOfEachCompressionReadsBack) {
  TempDir dir;
  for (const char* compression : {"zstd", "lz4", ""}) {
    const fs::path file = dir / (std::string("c_") + compression + ".mcap");
    write_mcap(file, compression, 300);
    const Rosbag2Reader reader(file);
    ASSERT_EQ(reader.topics().size(), 2u);
    EXPECT_EQ(reader.topic("/imu").messages, 300u);
    EXPECT_EQ(reader.topic("/imu").datatype, "sensor_msgs/msg/Imu");
    const ImuSeries imu = reader.read_imu("/imu");
    ASSERT_EQ(imu.size(), 300u) << compression;
    for (size_t i = 0; i < imu.size(); ++i) {
      EXPECT_EQ(imu[i].t_ns, kT0 + static_cast<TimeNs>(i) * 5000000LL);
      EXPECT_EQ(imu[i].gyro_rad_s.x(), 0.001 * i);
      EXPECT_EQ(imu[i].accel_m_s2.z(), 9.81);
    }
  }
}

TEST(Rosbag2Reader, WrongMagicNamesTheFile) {
  TempDir dir;
  write_mcap(dir / "a.mcap", "zstd", 10);
  std::string bytes = read_bytes(dir / "a.mcap");
  bytes[1] = 'X';
  write_bytes(dir / "a.mcap", bytes);
  expect_error([&] { Rosbag2Reader reader(dir / "a.mcap"); },
               {"a.mcap", "not an MCAP file", "89 58 43 41"});
  write_bytes(dir / "b.mcap", "");
  expect_error([&] { Rosbag2Reader reader(dir / "b.mcap"); }, {"b.mcap", "empty file"});
  write_bytes(dir / "c.db3", "this is not a database, not even close to one, at all........");
  expect_error([&] { Rosbag2Reader reader(dir / "c.db3"); }, {"c.db3", "SQLite"});
}

TEST(Rosbag2Reader, TruncatedMcapFailsNamingTopicAndMessageIndex) {
  TempDir dir;
  write_mcap(dir / "full.mcap", "zstd", 400);
  const std::string bytes = read_bytes(dir / "full.mcap");
  // Cut in the middle of the data: the summary and footer are gone, so the file is scanned;
  // the messages before the cut read, the first one after it fails.
  write_bytes(dir / "cut.mcap", bytes.substr(0, bytes.size() / 2));
  const Rosbag2Reader reader(dir / "cut.mcap");
  ASSERT_TRUE(reader.has_topic("/imu"));
  const size_t complete = reader.topic("/imu").messages;
  EXPECT_GT(complete, 0u);
  EXPECT_LT(complete, 400u);
  expect_error([&] { reader.read_imu("/imu"); },
               {"cut.mcap: topic '/imu' message " + std::to_string(complete), "truncated MCAP"});
  expect_error([&] { reader.read_imu("/late"); },
               {"no topic '/late'", "cut.mcap ends without its MCAP footer"});
  // Cut inside the Header: refused at open.
  write_bytes(dir / "head.mcap", bytes.substr(0, 12));
  expect_error([&] { Rosbag2Reader r(dir / "head.mcap"); }, {"head.mcap", "truncated MCAP"});
}

TEST(Rosbag2Reader, ChunkWithABadCrcFailsNamingTopicAndMessageIndex) {
  TempDir dir;
  write_mcap(dir / "crc.mcap", "", 400);  // uncompressed chunks: a flipped byte reaches the CRC
  std::string bytes = read_bytes(dir / "crc.mcap");
  const size_t hello = bytes.find("hello 200");
  ASSERT_NE(hello, std::string::npos);
  bytes[hello] = 'J';
  write_bytes(dir / "crc.mcap", bytes);
  const Rosbag2Reader reader(dir / "crc.mcap");  // the summary is intact: it opens
  bool failed = false;
  try {
    reader.for_each_message("/chatter", [](const auto&, size_t) {});
  } catch (const IoError& e) {
    failed = true;
    const std::string message = e.what();
    EXPECT_NE(message.find("crc.mcap: topic '/chatter' message "), std::string::npos) << message;
    EXPECT_NE(message.find("CRC mismatch"), std::string::npos) << message;
    // The failing message is the first of the damaged chunk: at most message 200.
    const size_t index = std::stoul(message.substr(message.find("message ") + 8));
    EXPECT_LE(index, 200u) << message;
    EXPECT_GT(index, 100u) << message;  // a 4 KiB chunk holds ~10 of each topic
  }
  EXPECT_TRUE(failed);
}

TEST(Rosbag2Reader, CdrLengthPastTheEndFailsNamingTopicAndMessageIndex) {
  TempDir dir;
  {
    sim::McapWriter w((dir / "cdr.mcap").string());
    const uint16_t imu = w.add_channel("/imu", w.add_schema("sensor_msgs/msg/Imu", "ros2msg", ""));
    for (int i = 0; i < 5; ++i) {
      std::vector<uint8_t> m = imu_cdr(kT0 + i, 0.0);
      if (i == 3) m[12] = 0xFF, m[13] = 0xFF;  // frame_id length 65535 + 4 in a ~330-byte message
      w.write(imu, kT0 + i, m);
    }
  }
  const Rosbag2Reader reader(dir / "cdr.mcap");
  expect_error([&] { reader.read_imu("/imu"); },
               {"cdr.mcap: topic '/imu' message 3", "header.frame_id", "runs past the end"});
}

TEST(Rosbag2Reader, UnknownTypeOnAMappedTopicFailsNamingTopicAndMessageIndex) {
  TempDir dir;
  write_mcap(dir / "types.mcap", "zstd", 10);
  const Rosbag2Reader reader(dir / "types.mcap");
  expect_error([&] { reader.read_imu("/chatter"); },
               {"types.mcap: topic '/chatter' message 0", "std_msgs/msg/String",
                "expected sensor_msgs/msg/Imu"});
  PointCloud cloud;
  expect_error([&] { reader.open_scans("/chatter", {})->next(cloud); },
               {"types.mcap: topic '/chatter' message 0", "expected sensor_msgs/msg/PointCloud2"});
  expect_error([&] { reader.read_imu("/nope"); }, {"types.mcap", "no topic '/nope'", "/chatter"});
}

TEST(Rosbag2Reader, Db3ReadsBackAndNamesItsErrors) {
  TempDir dir;
  {
    sim::Db3Writer w((dir / "x.db3").string());
    const int64_t imu = w.add_topic("/imu", "sensor_msgs/msg/Imu", "");
    const int64_t chatter = w.add_topic("/chatter", "std_msgs/msg/String", "");
    for (int i = 0; i < 50; ++i) {
      w.write(imu, kT0 + i, imu_cdr(kT0 + i * 1000, 0.5 * i));
      sim::CdrWriter s;
      s.string("x");
      w.write(chatter, kT0 + i, s.take());
    }
    std::vector<uint8_t> bad = imu_cdr(kT0 + 999999, 0);
    bad.resize(100);  // cut inside the covariances
    w.write(imu, kT0 + 60, bad);
  }
  const Rosbag2Reader reader(dir / "x.db3");
  EXPECT_EQ(reader.topic("/imu").messages, 51u);
  EXPECT_EQ(reader.topic("/chatter").datatype, "std_msgs/msg/String");
  expect_error([&] { reader.read_imu("/imu"); }, {"x.db3: topic '/imu' message 50", "CDR"});
  expect_error([&] { reader.read_dvl("/chatter"); },
               {"x.db3: topic '/chatter' message 0", "std_msgs/msg/String"});
}

TEST(Rosbag2Reader, FolderNeedsMetadataAndRefusesFileCompression) {
  TempDir dir;
  fs::create_directories(dir / "bag");
  expect_error([&] { Rosbag2Reader r(dir / "bag"); }, {"no metadata.yaml"});
  testing::write_text(dir / "bag" / "metadata.yaml",
                      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
                      "  relative_file_paths: [bag_0.mcap.zstd]\n  compression_format: zstd\n"
                      "  compression_mode: FILE\n");
  expect_error([&] { Rosbag2Reader r(dir / "bag"); }, {"metadata.yaml", "compression_mode FILE"});
  testing::write_text(dir / "bag" / "metadata.yaml",
                      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
                      "  relative_file_paths: [../outside.mcap]\n");
  expect_error([&] { Rosbag2Reader r(dir / "bag"); },
               {"relative_file_paths[0]", "inside the bag folder"});
}

}  // namespace
}  // namespace keel::io
