// Writes the fuzzers' seed corpora: small ROS 2 bags of every type keel-sim records, in MCAP
// (zstd, lz4 and uncompressed chunks; one cut short) and SQLite3, and their messages one per
// file for the CDR fuzzer (first byte: the type's index in fuzz_decode.h).
//   fuzz_seeds OUT_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/fuzz/fuzz_decode.h"
#include "tests/sim/bag2_writer.h"
#include "worker/io/byte_source.h"
#include "worker/io/mcap_reader.h"

namespace fs = std::filesystem;
using namespace keel;

namespace {

void record(sim::BagSink& bag) {
  const TimeNs t0 = 1700000000000000000LL;
  for (int i = 0; i < 3; ++i) {
    const TimeNs t = t0 + i * 100000000LL;
    bag.imu("/imu", "imu", t, Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0, 0, 9.81));
    bag.twist("/dvl", "dvl", t, Eigen::Vector3d(1, 0, 0), 0.01);
    PointCloud cloud;
    cloud.t_ns = t;
    for (int p = 0; p < 4; ++p) {
      cloud.xyz.emplace_back(static_cast<float>(p), 1.0f, 2.0f);
      cloud.intensity.push_back(10.0f * p);
      cloud.time_s.push_back(0.01f * p);
    }
    bag.cloud("/points", "lidar", cloud);
    bag.image("/image", "cam", t, cv::Mat(2, 3, CV_8UC1, cv::Scalar(7)));
    const StampedPose pose{t, make_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(i, 0, 0))};
    bag.pose("/pose", "world", pose);
    bag.odometry("/odom", "world", "base_link", pose);
  }
  bag.close();
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
    return 1;
  }
  const fs::path out = argv[1];
  fs::remove_all(out);
  for (const char* d : {"mcap", "db3", "cdr", "bags"}) fs::create_directories(out / d);
  for (const char* compression : {"zstd", "lz4", "none"}) {
    sim::Bag2Options o;
    o.compression = compression;
    sim::Bag2Writer bag((out / "bags" / compression).string(), o);
    record(bag);
    fs::copy_file(out / "bags" / compression / (std::string(compression) + "_0.mcap"),
                  out / "mcap" / (std::string(compression) + ".mcap"));
  }
  {
    const std::string whole = read(out / "mcap" / "zstd.mcap");
    std::ofstream(out / "mcap" / "cut.mcap", std::ios::binary)
        << whole.substr(0, whole.size() * 2 / 3);
    sim::Bag2Options o;
    o.storage = "sqlite3";
    sim::Bag2Writer bag((out / "bags" / "db3").string(), o);
    record(bag);
    fs::copy_file(out / "bags" / "db3" / "db3_0.db3", out / "db3" / "bag.db3");
  }
  // One message per type and file for the CDR fuzzer.
  io::McapReader reader(std::make_shared<io::FileBytes>(out / "mcap" / "none.mcap", "none.mcap"));
  auto cursor = reader.messages();
  io::McapMessage m;
  int n = 0;
  while (cursor.next(m)) {
    const auto& types = keel::fuzz::kTypes;
    for (size_t t = 0; t < sizeof(types) / sizeof(types[0]); ++t) {
      if (m.channel->schema_name != types[t]) continue;
      std::ofstream f(out / "cdr" / ("msg_" + std::to_string(n++)), std::ios::binary);
      f.put(static_cast<char>(t));
      f.write(reinterpret_cast<const char*>(m.data), static_cast<std::streamsize>(m.size));
    }
  }
  fs::remove_all(out / "bags");
  std::printf("fuzz_seeds: %d CDR messages, 4 MCAP files, 1 .db3 in %s\n", n, out.c_str());
  return 0;
}
