// Keel's ROS1 bag reader (worker/io/bag/ros1_bag.h) against ROS1's own python reader
// (Debian's python3-rosbag, tests/worker/io/rosbag_dump.py): on bags written by rosbag's C++
// library (keel-sim), by its python writer with each chunk compression (make_test_bag.py) and
// by Water Linked's A50 driver (KEEL_A50_BAGS), both readers give the same topics, types and
// counts, and per topic the same messages in the same order: record time, MD5 and bytes.
// Skips, saying so, without /usr/bin/python3 and python3-rosbag.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/sha256.h"
#include "io_test_util.h"
#include "tests/sim/simulator.h"
#include "worker/io/bag/bag_reader.h"
#include "worker/io/bag/byte_source.h"
#include "worker/io/bag/ros1_bag.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

bool have_python_rosbag() {
  return std::system("/usr/bin/python3 -c 'import rosbag' >/dev/null 2>&1") == 0;
}

// "sec nsec md5 size sha256" of one message.
std::string line_of(TimeNs t_ns, const std::string& md5, size_t size, const std::string& sha) {
  return std::to_string(t_ns / 1000000000) + " " + std::to_string(t_ns % 1000000000) + " " + md5 +
         " " + std::to_string(size) + " " + sha;
}

struct Reading {
  std::map<std::string, std::string> topics;                 // topic -> "type count"
  std::map<std::string, std::vector<std::string>> messages;  // topic -> lines, in order
};

Reading read_with_rosbag(const fs::path& bag) {
  const std::string command = "/usr/bin/python3 " + std::string(KEEL_SOURCE_DIR) +
                              "/tests/worker/io/rosbag_dump.py '" + bag.string() + "'";
  FILE* pipe = popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  std::string out;
  char buffer[1 << 16];
  for (size_t n; pipe && (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  EXPECT_EQ(pipe ? pclose(pipe) : -1, 0) << command;
  Reading r;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string x; std::getline(fields, x, '\t');) f.push_back(x);
    if (f.size() == 4 && f[0] == "T") r.topics[f[1]] = f[2] + " " + f[3];
    if (f.size() == 7 && f[0] == "M")
      r.messages[f[1]].push_back(f[2] + " " + f[3] + " " + f[4] + " " + f[5] + " " + f[6]);
  }
  return r;
}

Reading read_with_keel(const fs::path& bag) {
  Reading r;
  const BagReader reader(bag);
  for (const BagTopicInfo& t : reader.topics())
    r.topics[t.topic] = t.datatype + " " + std::to_string(t.messages);
  const Ros1Bag ros1(std::make_shared<FileBytes>(bag, bag.string()), bag.string());
  for (const BagTopicInfo& t : reader.topics()) {
    Ros1Bag::Cursor cursor = ros1.messages(t.topic);
    Ros1Message m;
    while (cursor.next(m))
      r.messages[t.topic].push_back(
          line_of(m.time_ns, m.connection->md5sum, m.size,
                  sha256_bytes(std::string(reinterpret_cast<const char*>(m.data), m.size))));
    // The public interface gives the same bytes and times.
    size_t i = 0;
    reader.for_each_raw_message(t.topic, [&](const BagRawMessage& raw, size_t index) {
      EXPECT_EQ(index, i);
      EXPECT_EQ(raw.type, t.datatype);
      const std::string line = r.messages[t.topic].at(i++);
      EXPECT_EQ(line.substr(0, line.find(' ', line.find(' ') + 1)),
                std::to_string(raw.log_time_ns / 1000000000) + " " +
                    std::to_string(raw.log_time_ns % 1000000000));
      EXPECT_EQ(line.substr(line.rfind(' ') + 1),
                sha256_bytes(std::string(reinterpret_cast<const char*>(raw.data), raw.size)));
      return true;
    });
    EXPECT_EQ(i, r.messages[t.topic].size());
  }
  return r;
}

void expect_same_reading(const fs::path& bag) {
  SCOPED_TRACE(bag.string());
  const Reading expected = read_with_rosbag(bag);
  const Reading actual = read_with_keel(bag);
  ASSERT_FALSE(expected.topics.empty());
  EXPECT_EQ(actual.topics, expected.topics);
  for (const auto& [topic, lines] : expected.messages) {
    SCOPED_TRACE(topic);
    const auto it = actual.messages.find(topic);
    ASSERT_NE(it, actual.messages.end());
    ASSERT_EQ(it->second.size(), lines.size());
    for (size_t i = 0; i < lines.size(); ++i) ASSERT_EQ(it->second[i], lines[i]) << "message " << i;
  }
  EXPECT_EQ(actual.messages.size(), expected.messages.size());
}

#define SKIP_WITHOUT_PYTHON_ROSBAG() \
  if (!have_python_rosbag()) GTEST_SKIP() << "/usr/bin/python3 with python3-rosbag unavailable"

TEST(Ros1BagReference, KeelSimBag) {
  SKIP_WITHOUT_PYTHON_ROSBAG();
  TempDir dir;
  sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.seed = 5;
  o.duration_s = 6.0;
  o.sensors = {"imu", "dvl", "lidar_h", "camera"};
  o.gnss = true;
  o.out_dir = (dir / "sim").string();
  o.write_bag = true;
  sim::run_simulation(o);
  expect_same_reading(dir / "sim" / "mission.bag");
}

TEST(Ros1BagReference, PythonWrittenBagsOfEachCompression) {
  SKIP_WITHOUT_PYTHON_ROSBAG();
  for (const char* compression : {"none", "bz2", "lz4"}) {
    TempDir dir;
    const fs::path bag = dir / ("mission_" + std::string(compression) + ".bag");
    const std::string command = "/usr/bin/python3 " + std::string(KEEL_SOURCE_DIR) +
                                "/tests/worker/io/make_test_bag.py " + bag.string() + " " +
                                compression;
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    expect_same_reading(bag);
  }
}

TEST(Ros1BagReference, WaterLinkedA50Bags) {
  SKIP_WITHOUT_PYTHON_ROSBAG();
  const char* folder = std::getenv("KEEL_A50_BAGS");
  if (!folder || !*folder)
    GTEST_SKIP() << "KEEL_A50_BAGS is not set (a folder with Water Linked's A50 bags)";
  for (const char* name :
       {"dvl.bag", "dvl_circle.bag", "dvl_fast_rectangle.bag", "dvl_slow_rectangle.bag"})
    expect_same_reading(fs::path(folder) / name);
}

}  // namespace
}  // namespace keel::io
