// Streaming throughput of the mission readers: points/s from PCD/PLY scan folders and from a
// bag's PointCloud2 topic, ROS1 and ROS 2 (MCAP zstd, MCAP lz4, SQLite3) (target >= 1 M
// points/s each), rows/s of an IMU CSV. The data are generated here, in a temporary folder;
// the same sweeps go into every bag, and the ROS 2 / ROS1 ratios are printed at the end.
// Run: build/tests/bench/bench_io
#include <benchmark/benchmark.h>

#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include "tests/sim/bag2_writer.h"

#include "worker/io/bag/bag_reader.h"
#include "worker/io/bag/rosbag2_reader.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/scan_source.h"
#include "worker/io/stream_csv.h"

namespace {

namespace fs = std::filesystem;
using namespace keel;
using namespace keel::io;

constexpr int kScans = 20;
constexpr int kPointsPerScan = 115200;  // a 64-beam lidar at 1800 columns
constexpr TimeNs kT0 = 1700000000LL * 1000000000LL;

const PointTimeEncoding kVelodyneTime{
    {"time", proto::TimeUnit::kSeconds, proto::TimeReference::kScanStart}, FieldType::kFloat32};

fs::path bench_dir() {
  static const fs::path dir = [] {
    fs::path d =
        fs::temp_directory_path() / ("keel-io-bench-" + std::to_string(std::random_device{}()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

PointCloud make_sweep(int k) {
  PointCloud c;
  c.t_ns = kT0 + static_cast<TimeNs>(k) * 100000000;
  std::mt19937 rng(k);
  std::uniform_real_distribution<float> range(1.0f, 60.0f);
  for (int i = 0; i < kPointsPerScan; ++i) {
    const float azimuth = 2.0f * static_cast<float>(M_PI) * (i / 64) / 1800.0f;
    const float elevation = (static_cast<float>(i % 64) - 32.0f) * 0.01f;
    const float r = range(rng);
    c.xyz.emplace_back(r * std::cos(azimuth), r * std::sin(azimuth), r * elevation);
    c.intensity.push_back(static_cast<float>(i % 255));
    c.ring.push_back(static_cast<uint16_t>(i % 64));
    c.time_s.push_back(0.1f * static_cast<float>(i / 64) / 1800.0f);
  }
  return c;
}

ScanReadOptions read_options() {
  ScanReadOptions o;
  o.point_time = kVelodyneTime.spec;
  o.sweep_period_s = 0.1;
  return o;
}

fs::path scan_folder(const std::string& name, const std::string& extension, ScanEncoding encoding) {
  const fs::path folder = bench_dir() / name;
  if (fs::exists(folder / "index.csv")) return folder;
  fs::create_directories(folder);
  std::vector<IndexEntry> index;
  for (int k = 0; k < kScans; ++k) {
    const PointCloud c = make_sweep(k);
    const fs::path file = folder / ("scan_" + std::to_string(k) + extension);
    write_scan_file(file, c, {encoding, kVelodyneTime});
    index.push_back({c.t_ns, file, 0});
  }
  write_folder_index(folder, index);
  return folder;
}

fs::path point_cloud_bag() {
  const fs::path path = bench_dir() / "points.bag";
  if (fs::exists(path)) return path;
  rosbag::Bag bag(path.string(), rosbag::bagmode::Write);
  for (int k = 0; k < kScans; ++k) {
    const PointCloud c = make_sweep(k);
    const PackedCloud packed = pack_cloud(c, kVelodyneTime);
    sensor_msgs::PointCloud2 msg;
    msg.header.stamp = ros::Time(c.t_ns / 1000000000, c.t_ns % 1000000000);
    msg.header.frame_id = "lidar";
    msg.height = 1;
    msg.width = static_cast<uint32_t>(packed.num_points);
    msg.point_step = static_cast<uint32_t>(packed.point_step);
    msg.row_step = msg.point_step * msg.width;
    msg.is_dense = true;
    const uint8_t datatypes[] = {1, 2, 3, 4, 5, 6, 0, 0, 7, 8};  // FieldType -> PointField
    for (const auto& f : packed.fields) {
      sensor_msgs::PointField field;
      field.name = f.name;
      field.offset = static_cast<uint32_t>(f.offset);
      field.datatype = datatypes[static_cast<int>(f.type)];
      field.count = 1;
      msg.fields.push_back(field);
    }
    msg.data = packed.data;
    bag.write("/lidar/points", msg.header.stamp, msg);
  }
  bag.close();
  return path;
}

// A rosbag2 folder of the same sweeps (keel-sim's writer: x y z intensity ring time).
fs::path point_cloud_bag2(const std::string& storage, const std::string& compression) {
  const fs::path path = bench_dir() / ("bag2_" + storage + "_" + compression);
  if (fs::exists(path / "metadata.yaml")) return path;
  sim::Bag2Options options;
  options.storage = storage;
  options.compression = compression;
  sim::Bag2Writer bag(path.string(), options);
  for (int k = 0; k < kScans; ++k) bag.cloud("/lidar/points", "lidar", make_sweep(k));
  bag.close();
  return path;
}

// points/s of each bag benchmark's last run, for the ratios printed at the end.
std::map<std::string, double>& rates() {
  static std::map<std::string, double> r;
  return r;
}

void count_points(benchmark::State& state, ScanSource& source, size_t& points) {
  PointCloud cloud;
  while (source.next(cloud)) points += cloud.size();
  benchmark::DoNotOptimize(cloud.xyz.data());
}

void stream_folder(benchmark::State& state, const fs::path& folder) {
  size_t points = 0;
  for (auto _ : state) {
    ScanFolderReader reader(folder, read_options());
    count_points(state, reader, points);
  }
  state.counters["points/s"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
}

void BM_StreamPcdBinary(benchmark::State& state) {
  stream_folder(state, scan_folder("pcd_binary", ".pcd", ScanEncoding::kBinary));
}
void BM_StreamPcdCompressed(benchmark::State& state) {
  stream_folder(state, scan_folder("pcd_compressed", ".pcd", ScanEncoding::kBinaryCompressed));
}
void BM_StreamPlyBinary(benchmark::State& state) {
  stream_folder(state, scan_folder("ply_binary", ".ply", ScanEncoding::kBinary));
}
void BM_StreamPcdAscii(benchmark::State& state) {
  stream_folder(state, scan_folder("pcd_ascii", ".pcd", ScanEncoding::kAscii));
}

void stream_bag(benchmark::State& state, const fs::path& bag, const std::string& name) {
  size_t points = 0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    const auto reader = open_bag(bag);
    auto source = reader->open_scans("/lidar/points", read_options());
    count_points(state, *source, points);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rates()[name] = static_cast<double>(points) / seconds;
  state.counters["points/s"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
}

void BM_StreamBagPointCloud2(benchmark::State& state) {
  stream_bag(state, point_cloud_bag(), "ROS1 bag");
}
void BM_StreamMcapZstdPointCloud2(benchmark::State& state) {
  stream_bag(state, point_cloud_bag2("mcap", "zstd"), "ROS 2 MCAP zstd");
}
void BM_StreamMcapLz4PointCloud2(benchmark::State& state) {
  stream_bag(state, point_cloud_bag2("mcap", "lz4"), "ROS 2 MCAP lz4");
}
void BM_StreamDb3PointCloud2(benchmark::State& state) {
  stream_bag(state, point_cloud_bag2("sqlite3", "none"), "ROS 2 SQLite3");
}

void BM_ReadImuCsv(benchmark::State& state) {
  const fs::path path = bench_dir() / "imu.csv";
  if (!fs::exists(path)) {
    ImuSeries imu;
    for (int i = 0; i < 720000; ++i)  // one hour at 200 Hz
      imu.push_back({kT0 + i * 5000000LL,
                     {1e-3 * std::sin(i), 2e-3, -1e-3},
                     {0.01 * i / 720000.0, 0.2, 9.81}});
    write_imu_csv(path, imu);
  }
  size_t rows = 0;
  for (auto _ : state) rows += read_imu_csv(path).size();
  state.counters["rows/s"] =
      benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsRate);
}

BENCHMARK(BM_StreamPcdBinary)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamPcdCompressed)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamPlyBinary)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamPcdAscii)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_StreamBagPointCloud2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamMcapZstdPointCloud2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamMcapLz4PointCloud2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamDb3PointCloud2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadImuCsv)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  const auto& r = rates();
  if (r.count("ROS1 bag")) {
    std::printf("\nPointCloud2 streaming, same %d sweeps of %d points (target >= 1e6 points/s):\n",
                kScans, kPointsPerScan);
    for (const auto& [name, rate] : r)
      std::printf("  %-18s %6.2f M points/s  (%.2f x ROS1)\n", name.c_str(), rate / 1e6,
                  rate / r.at("ROS1 bag"));
  }
  std::error_code ec;
  fs::remove_all(bench_dir(), ec);
  return 0;
}
