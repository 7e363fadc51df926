// An independent reader of the point files Keel writes: Open3D (Debian's python3-open3d, run
// through /usr/bin/python3) reads binary PLY, PCD binary, PCD binary_compressed and PCD ascii
// written by write_scan_file, and every point it returns equals Keel's. The cloud is the real
// VLP-16 sweep (shared/data) with intensity, ring and per-point time (fields Open3D skips) plus
// points with awkward float values. Skips, saying why, when Open3D or the data is absent.
// (PCL's reader is the other independent one: pcd_pcl_parity_test.cc.)
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "worker/io/cloud/scan_file.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;

// Reads `in` with Open3D and writes its points as little-endian float64 x y z to `out`.
constexpr const char* kOpen3dDump =
    "import sys, numpy as np, open3d as o3d\n"
    "pc = o3d.io.read_point_cloud(sys.argv[1], remove_nan_points=False, "
    "remove_infinite_points=False)\n"
    "np.asarray(pc.points, dtype='<f8').tofile(sys.argv[2])\n";

bool open3d_available() {
  return std::system("/usr/bin/python3 -c 'import open3d' >/dev/null 2>&1") == 0;
}

PointCloud test_cloud() {
  PointCloud cloud =
      read_scan_file(fs::path(KEEL_SHARED_DIR) / "data" / "test_scan_vlp16.pcd", 0, {});
  // Values a decimal writer or a float parser could get wrong: the smallest normal and
  // subnormal floats, the largest finite, the neighbours of 0.1, negative zero, large integers.
  const float awkward[] = {std::numeric_limits<float>::min(),
                           std::numeric_limits<float>::denorm_min(),
                           std::numeric_limits<float>::max(),
                           -std::numeric_limits<float>::max(),
                           std::nextafter(0.1f, 0.0f),
                           std::nextafter(0.1f, 1.0f),
                           -0.0f,
                           16777217.0f,
                           -123456.789f};
  for (const float a : awkward)
    for (const float b : {1.0f / 3.0f, -2.5e-7f}) {
      cloud.xyz.emplace_back(a, b, -a);
      if (cloud.has_intensity()) cloud.intensity.push_back(1.0f);
      if (cloud.has_ring()) cloud.ring.push_back(0);
      if (cloud.has_time()) cloud.time_s.push_back(0.0f);
    }
  return cloud;
}

class Open3dReadsKeel : public ::testing::TestWithParam<std::pair<const char*, ScanEncoding>> {};

TEST_P(Open3dReadsKeel, EveryPointEqual) {
  const fs::path scan = fs::path(KEEL_SHARED_DIR) / "data" / "test_scan_vlp16.pcd";
  if (!fs::exists(scan)) GTEST_SKIP() << scan << " absent";
  if (!open3d_available())
    GTEST_SKIP() << "no independent reader: Open3D is not importable by /usr/bin/python3 "
                    "(Debian: python3-open3d)";
  const PointCloud cloud = test_cloud();
  ASSERT_GT(cloud.size(), 25000u);

  const auto [extension, encoding] = GetParam();
  const fs::path dir =
      fs::temp_directory_path() / ("keel_open3d_reads_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / (std::string("cloud") + extension);
  const fs::path dump = dir / "points.f64";
  const fs::path script = dir / "dump.py";
  std::ofstream(script) << kOpen3dDump;
  ScanWriteOptions options;
  options.encoding = encoding;
  options.time = PointTimeEncoding{
      proto::PointTimeSpec{"time", proto::TimeUnit::kSeconds, proto::TimeReference::kScanStart},
      FieldType::kFloat32};
  write_scan_file(file, cloud, options);
  const std::string command = "/usr/bin/python3 '" + script.string() + "' '" + file.string() +
                              "' '" + dump.string() + "' > '" + (dir / "open3d.log").string() +
                              "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "see " << dir / "open3d.log";

  std::ifstream in(dump, std::ios::binary);
  std::vector<double> theirs(3 * cloud.size() + 1);
  in.read(reinterpret_cast<char*>(theirs.data()), theirs.size() * sizeof(double));
  ASSERT_EQ(static_cast<size_t>(in.gcount()), 3 * cloud.size() * sizeof(double))
      << "Open3D returned a different number of points";
  size_t unequal = 0;
  for (size_t i = 0; i < cloud.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      // Open3D holds doubles: a float widened, or parsed from Keel's decimal text. Equal means
      // the same float, sign of zero included.
      const float ours = cloud.xyz[i][k];
      const float read = static_cast<float>(theirs[3 * i + k]);
      if (read != ours || std::signbit(read) != std::signbit(ours)) {
        if (++unequal <= 5)
          ADD_FAILURE() << extension << " point " << i << " axis " << k << ": Keel " << ours
                        << ", Open3D " << theirs[3 * i + k];
      }
    }
  EXPECT_EQ(unequal, 0u);
  fs::remove_all(dir);
}

std::string case_name(const ::testing::TestParamInfo<std::pair<const char*, ScanEncoding>>& info) {
  static const char* const kNames[] = {"ascii", "binary", "binary_compressed"};
  return std::string(info.param.first + 1) + "_" + kNames[static_cast<int>(info.param.second)];
}

INSTANTIATE_TEST_SUITE_P(Encodings, Open3dReadsKeel,
                         ::testing::Values(std::make_pair(".ply", ScanEncoding::kBinary),
                                           std::make_pair(".pcd", ScanEncoding::kBinary),
                                           std::make_pair(".pcd", ScanEncoding::kBinaryCompressed),
                                           std::make_pair(".pcd", ScanEncoding::kAscii)),
                         case_name);

}  // namespace
}  // namespace keel::io
