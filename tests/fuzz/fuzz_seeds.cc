// Writes the fuzzers' seed corpora, one folder per harness:
// - small ROS 2 bags of every type keel-sim records, in MCAP (zstd, lz4 and uncompressed
//   chunks; one cut short) and SQLite3, and their messages one per file for the CDR fuzzer
//   (first byte: the type's index in fuzz_decode.h);
// - the same as whole ROS1 bags with bz2, lz4 and uncompressed chunks;
// - valid Draco files (first byte: 0 a point cloud, 1 a mesh), written by Keel's encoder at
//   several compression levels with each kind of attribute its maps and hulls carry, and small
//   PNG and JPEG images of each pixel format Keel reads. Debian's Draco, libpng and libjpeg are
//   not instrumented: libFuzzer sees only Keel's side of them, and without valid files would
//   never get past their headers;
// - a file of every encoding of the scan, mesh, trajectory, CSV and tar readers (file_seeds.h)
//   and a valid document of every JSON contract (contract_seeds.h).
//   fuzz_seeds OUT_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "tests/fuzz/contract_seeds.h"
#include "tests/fuzz/file_seeds.h"
#include "tests/fuzz/fuzz_decode.h"
#include "tests/sim/bag2_writer.h"
#include "tests/sim/bag_writer.h"
#include "worker/io/bag/bag_reader.h"
#include "worker/io/bag/byte_source.h"
#include "worker/io/bag/mcap_reader.h"
#include "worker/io/draco/draco_codec.h"

namespace fs = std::filesystem;
using namespace keel;

namespace {

// A Water Linked A50 message with four beams, `valid` of them locked.
io::A50Dvl a50(TimeNs t, int valid) {
  io::A50Dvl m;
  m.stamp_ns = t;
  m.velocity_m_s = {0.3, 0.1, 0.0};
  m.fom_m_s = 0.002;
  m.velocity_valid = valid == 4;
  for (int k = 0; k < 4; ++k) m.beams.push_back({k, 0.1 * k, 2.0, -30.0, -90.0, k < valid});
  return m;
}

template <typename Bag>  // sim::BagWriter or sim::Bag2Writer
void record(Bag& bag) {
  const TimeNs t0 = 1700000000000000000LL;
  for (int i = 0; i < 3; ++i) {
    const TimeNs t = t0 + i * 100000000LL;
    bag.a50_dvl("/dvl/data", "dvl", a50(t, 4 - i));
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

void write_seed(const fs::path& path, char selector, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.put(selector);
  f << bytes;
}

// A few points and a small mesh, each at compression levels 0 (sequential), 5 and 10 (the
// kd-tree and edgebreaker coders), with the fields, labels and no-data metadata Keel writes.
int draco_seeds(const fs::path& dir) {
  PointCloud part_a, part_b;
  for (int i = 0; i < 12; ++i) {
    part_a.xyz.emplace_back(0.1f * i, 0.3f * (i % 4), 0.05f * i * i);
    part_a.intensity.push_back(static_cast<float>(i));
    part_b.xyz.emplace_back(-0.2f * i, 1.0f, 0.5f * (i % 3));
    part_b.intensity.push_back(100.0f - i);
  }
  io::PartsAttributes attributes;
  attributes.label_name = "sensor";
  attributes.part_labels = {"multibeam", "camera"};
  std::vector<float> height(24);
  for (size_t i = 0; i < height.size(); ++i) height[i] = i % 5 == 0 ? -1.0f : 0.01f * i;
  attributes.fields = {{"height_m", height}};
  attributes.fields_no_data = {-1.0f};

  TriangleMesh mesh;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) mesh.vertices.emplace_back(c, r, 0.1 * r * c);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int v = 4 * r + c;
      mesh.faces.emplace_back(v, v + 1, v + 5);
      mesh.faces.emplace_back(v, v + 5, v + 4);
    }
  std::vector<float> deviation(mesh.vertices.size());
  for (size_t i = 0; i < deviation.size(); ++i) deviation[i] = 0.001f * i;

  int n = 0;
  for (int level : {0, 5, 10}) {
    io::DracoOptions o;
    o.compression_level = level;
    const std::string l = std::to_string(level);
    write_seed(dir / ("cloud_" + l), 0, io::encode_draco_point_cloud(part_a, {}, o).bytes);
    write_seed(dir / ("parts_" + l), 0,
               io::encode_draco_point_cloud({&part_a, &part_b}, o, attributes).bytes);
    write_seed(dir / ("mesh_" + l), 1,
               io::encode_draco_mesh(mesh, {{"deviation", deviation}}, o).bytes);
    n += 3;
  }
  io::DracoOptions lossless;
  lossless.field_bits = 0;
  write_seed(dir / "mesh_lossless_fields", 1,
             io::encode_draco_mesh(mesh, {{"deviation", deviation}}, lossless).bytes);
  return n + 1;
}

// Gray, RGB, RGBA and 16-bit PNGs; baseline and progressive JPEGs.
int image_seeds(const fs::path& dir) {
  cv::Mat gray(6, 8, CV_8UC1), bgr(6, 8, CV_8UC3), bgra(5, 7, CV_8UC4), deep(4, 5, CV_16UC1);
  cv::randu(gray, 0, 255);
  cv::randu(bgr, 0, 255);
  cv::randu(bgra, 0, 255);
  cv::randu(deep, 0, 65535);
  const std::vector<std::tuple<std::string, cv::Mat, std::vector<int>>> images = {
      {"gray.png", gray, {}},
      {"rgb.png", bgr, {cv::IMWRITE_PNG_COMPRESSION, 9}},
      {"rgba.png", bgra, {}},
      {"deep.png", deep, {}},
      {"gray.jpg", gray, {cv::IMWRITE_JPEG_QUALITY, 90}},
      {"rgb.jpg", bgr, {}},
      {"progressive.jpg", bgr, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
  };
  for (const auto& [name, mat, params] : images) {
    std::vector<uint8_t> bytes;
    cv::imencode(fs::path(name).extension().string(), mat, bytes, params);
    std::ofstream(dir / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
  }
  return static_cast<int>(images.size());
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
  for (const char* d : {"mcap", "db3", "cdr", "draco", "image", "scan_file", "mesh", "trajectory",
                        "csv_streams", "bundle_check", "json_contracts", "bag", "bags", "a50"})
    fs::create_directories(out / d);
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
      if (m.channel->schema_name == std::string("dvl_msgs/msg/DVL")) {  // a50_fuzz: odd = CDR
        std::ofstream a(out / "a50" / ("cdr_" + std::to_string(n)), std::ios::binary);
        a.put(1);
        a.write(reinterpret_cast<const char*>(m.data), static_cast<std::streamsize>(m.size));
      }
      std::ofstream f(out / "cdr" / ("msg_" + std::to_string(n++)), std::ios::binary);
      f.put(static_cast<char>(t));
      f.write(reinterpret_cast<const char*>(m.data), static_cast<std::streamsize>(m.size));
    }
  }
  fs::remove_all(out / "bags");
  // ROS1 bags, whole: rosbag reads a bag's index from its end, so a bag cut short is refused
  // before any message is read.
  const std::pair<const char*, sim::BagCompression> ros1[] = {
      {"none.bag", sim::BagCompression::kNone},
      {"bz2.bag", sim::BagCompression::kBz2},
      {"lz4.bag", sim::BagCompression::kLz4}};
  for (const auto& [name, compression] : ros1) {
    {
      sim::BagWriter bag((out / "bag" / name).string(), compression);
      record(bag);
    }
    const io::BagReader check(out / "bag" / name);  // throws when Keel cannot read it
    if (check.topics().size() != 7) {
      std::fprintf(stderr, "fuzz_seeds: %s has %zu topics, not 7\n", name, check.topics().size());
      return 1;
    }
  }
  const int drc = draco_seeds(out / "draco");
  const int images = image_seeds(out / "image");
  int scans = 0, meshes = 0, trajectories = 0, csvs = 0, bundles = 0, contracts = 0;
  try {
    scans = keel::fuzz::write_scan_seeds(out / "scan_file");
    meshes = keel::fuzz::write_mesh_seeds(out / "mesh");
    trajectories = keel::fuzz::write_trajectory_seeds(out / "trajectory");
    csvs = keel::fuzz::write_csv_seeds(out / "csv_streams");
    bundles = keel::fuzz::write_bundle_seeds(out / "bundle_check");
    contracts = keel::fuzz::write_contract_seeds(out / "json_contracts");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
  }
  std::printf(
      "fuzz_seeds: %d CDR messages, 4 MCAP files, 1 .db3, %d Draco files, %d images, %d scan, "
      "%d mesh, %d trajectory, %d CSV, %d bundle and %d JSON contract seeds, 3 ROS1 bags in %s\n",
      n, drc, images, scans, meshes, trajectories, csvs, bundles, contracts, out.c_str());
  return 0;
}
