// Point file I/O in memory speed terms (issue 35): a 1 M-point cloud (x, y, z, intensity, ring,
// time: 22 bytes a point) written and read as binary PLY, binary PCD and binary_compressed PCD
// by Keel, and by PCL in the same process (the peer), warm page cache; GB/s of file bytes
// and Keel / PCL ratios. Each run reads into a fresh cloud: on a virtual machine the first
// touch of fresh pages dominates (a page fault costs tens of microseconds), so these figures
// move with what the allocator reuses. Run: build/tests/bench/bench_point_io [points]
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

#include "worker/io/cloud/scan_file.h"

namespace {

namespace fs = std::filesystem;
using namespace keel;
using namespace keel::io;

double best_seconds(const std::function<void()>& run, int repeats = 5) {
  double best = 1e9;
  for (int i = 0; i < repeats; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    best = std::min(
        best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

PointCloud make_cloud(size_t n) {
  std::mt19937 rng(5);
  std::normal_distribution<float> xyz(0.0f, 20.0f);
  PointCloud cloud;
  cloud.t_ns = 1700000000000000000;
  for (size_t i = 0; i < n; ++i) {
    cloud.xyz.emplace_back(xyz(rng), xyz(rng), xyz(rng));
    cloud.intensity.push_back(static_cast<float>(i % 256));
    cloud.ring.push_back(static_cast<uint16_t>(i % 16));
    cloud.time_s.push_back(0.1f * static_cast<float>(i % 1000) / 1000.0f);
  }
  return cloud;
}

}  // namespace

int main(int argc, char** argv) {
  const size_t n = argc > 1 ? std::stoul(argv[1]) : 1000000;
  const fs::path dir = fs::temp_directory_path() / "keel-bench-point-io";
  fs::create_directories(dir);
  const PointCloud cloud = make_cloud(n);
  const proto::PointTimeSpec spec{"time", proto::TimeUnit::kSeconds,
                                  proto::TimeReference::kScanStart};
  ScanReadOptions read_options;
  read_options.point_time = spec;
  std::printf("%zu points, best of 5 runs, warm page cache\n", n);
  std::printf("%-28s %10s %10s %9s %9s %8s\n", "format", "keel (s)", "pcl (s)", "keel GB/s",
              "pcl GB/s", "pcl/keel");

  struct Case {
    const char* name;
    const char* file;
    ScanEncoding encoding;
  };
  const Case cases[] = {{"ply binary", "c.ply", ScanEncoding::kBinary},
                        {"pcd binary", "c.pcd", ScanEncoding::kBinary},
                        {"pcd binary_compressed", "z.pcd", ScanEncoding::kBinaryCompressed}};
  for (const Case& c : cases) {
    const fs::path path = dir / c.file;
    const ScanWriteOptions write_options{c.encoding, PointTimeEncoding{spec, FieldType::kFloat32}};
    const double keel_write = best_seconds([&] { write_scan_file(path, cloud, write_options); });
    const double bytes = static_cast<double>(fs::file_size(path));
    size_t points_read = 0;
    const double keel_read =
        best_seconds([&] { points_read = read_scan_file(path, cloud.t_ns, read_options).size(); });
    if (points_read != n) std::printf("  keel read %zu points, expected %zu\n", points_read, n);
    // Each side reads into a fresh cloud every run, as a program reading a file does.
    pcl::PCLPointCloud2 pcl_cloud;
    const bool ply = c.file[2] == 'p' && c.file[3] == 'l';
    const double pcl_read = best_seconds([&] {
      pcl::PCLPointCloud2 fresh;
      if (ply)
        pcl::io::loadPLYFile(path.string(), fresh);
      else
        pcl::io::loadPCDFile(path.string(), fresh);
      pcl_cloud = std::move(fresh);
    });
    const fs::path pcl_path = dir / (std::string("pcl_") + c.file);
    const double pcl_write = best_seconds([&] {
      if (ply)
        pcl::io::savePLYFile(pcl_path.string(), pcl_cloud, Eigen::Vector4f::Zero(),
                             Eigen::Quaternionf::Identity(), true);
      else if (c.encoding == ScanEncoding::kBinary)
        pcl::PCDWriter().writeBinary(pcl_path.string(), pcl_cloud);
      else
        pcl::PCDWriter().writeBinaryCompressed(pcl_path.string(), pcl_cloud);
    });
    const double gb = bytes / 1e9;
    std::printf("%-28s %10.4f %10.4f %9.2f %9.2f %8.1f\n", (std::string(c.name) + " read").c_str(),
                keel_read, pcl_read, gb / keel_read, gb / pcl_read, pcl_read / keel_read);
    std::printf("%-28s %10.4f %10.4f %9.2f %9.2f %8.1f\n", (std::string(c.name) + " write").c_str(),
                keel_write, pcl_write, gb / keel_write, gb / pcl_write, pcl_write / keel_write);
  }
  fs::remove_all(dir);
  return 0;
}
