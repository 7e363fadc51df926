// Keel's own PCD reader and writer (worker/io/cloud/pcd_file.cc) against PCL's: what Keel
// writes, PCL reads with every value equal, in each encoding; what PCL writes, Keel reads;
// Keel's own round trips are bit for bit. And LZF (lzf.h) on its own.
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <cstring>
#include <filesystem>
#include <random>

#include "worker/io/cloud/lzf.h"
#include "worker/io/cloud/scan_file.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() / "keel-pcd-pcl-parity";
  fs::create_directories(dir);
  return dir;
}

PointCloud random_cloud(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> xyz(0.0f, 30.0f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  PointCloud cloud;
  cloud.t_ns = 1700000000123456789;
  for (size_t i = 0; i < n; ++i) {
    cloud.xyz.emplace_back(xyz(rng), xyz(rng), xyz(rng));
    cloud.intensity.push_back(255.0f * unit(rng));
    cloud.ring.push_back(static_cast<uint16_t>(i % 16));
    cloud.time_s.push_back(0.1f * static_cast<float>(i) / static_cast<float>(n));
  }
  return cloud;
}

ScanWriteOptions with_time(ScanEncoding encoding) {
  return {encoding, PointTimeEncoding{proto::PointTimeSpec{"time", proto::TimeUnit::kSeconds,
                                                           proto::TimeReference::kScanStart},
                                      FieldType::kFloat32}};
}

ScanReadOptions read_time() {
  ScanReadOptions o;
  o.point_time =
      proto::PointTimeSpec{"time", proto::TimeUnit::kSeconds, proto::TimeReference::kScanStart};
  return o;
}

template <typename T>
T field_value(const pcl::PCLPointCloud2& cloud, const std::string& name, size_t point) {
  for (const auto& f : cloud.fields)
    if (f.name == name) {
      T value;
      std::memcpy(&value, cloud.data.data() + point * cloud.point_step + f.offset, sizeof value);
      return value;
    }
  ADD_FAILURE() << "no field " << name;
  return T{};
}

const ScanEncoding kEncodings[] = {ScanEncoding::kAscii, ScanEncoding::kBinary,
                                   ScanEncoding::kBinaryCompressed};

TEST(PcdPclParity, PclReadsWhatKeelWritesValueForValue) {
  const PointCloud cloud = random_cloud(5000, 1);
  for (ScanEncoding encoding : kEncodings) {
    SCOPED_TRACE(static_cast<int>(encoding));
    const fs::path path = scratch() / "keel_written.pcd";
    write_pcd(path, cloud, with_time(encoding));
    pcl::PCLPointCloud2 pcl_cloud;
    ASSERT_EQ(pcl::io::loadPCDFile(path.string(), pcl_cloud), 0);
    ASSERT_EQ(pcl_cloud.width * pcl_cloud.height, cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      ASSERT_EQ(field_value<float>(pcl_cloud, "x", i), cloud.xyz[i].x()) << i;
      ASSERT_EQ(field_value<float>(pcl_cloud, "y", i), cloud.xyz[i].y()) << i;
      ASSERT_EQ(field_value<float>(pcl_cloud, "z", i), cloud.xyz[i].z()) << i;
      ASSERT_EQ(field_value<float>(pcl_cloud, "intensity", i), cloud.intensity[i]) << i;
      ASSERT_EQ(field_value<uint16_t>(pcl_cloud, "ring", i), cloud.ring[i]) << i;
      ASSERT_EQ(field_value<float>(pcl_cloud, "time", i), cloud.time_s[i]) << i;
    }
  }
}

TEST(PcdPclParity, KeelReadsWhatPclWrites) {
  const PointCloud cloud = random_cloud(4000, 2);
  const fs::path keel_path = scratch() / "reference.pcd";
  write_pcd(keel_path, cloud, with_time(ScanEncoding::kBinary));
  pcl::PCLPointCloud2 pcl_cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(keel_path.string(), pcl_cloud), 0);
  pcl::PCDWriter writer;
  for (int encoding = 0; encoding < 3; ++encoding) {
    SCOPED_TRACE(encoding);
    const fs::path path = scratch() / "pcl_written.pcd";
    const std::string file = path.string();
    const int status = encoding == 0   ? writer.writeASCII(file, pcl_cloud, Eigen::Vector4f::Zero(),
                                                           Eigen::Quaternionf::Identity(), 9)
                       : encoding == 1 ? writer.writeBinary(file, pcl_cloud)
                                       : writer.writeBinaryCompressed(file, pcl_cloud);
    ASSERT_EQ(status, 0);
    const PointCloud back = read_pcd(path, cloud.t_ns, read_time());
    ASSERT_EQ(back.size(), cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      ASSERT_EQ(back.xyz[i], cloud.xyz[i]) << i;  // 9 significant digits round-trip a float
      ASSERT_EQ(back.intensity[i], cloud.intensity[i]) << i;
      ASSERT_EQ(back.ring[i], cloud.ring[i]) << i;
      ASSERT_EQ(back.time_s[i], cloud.time_s[i]) << i;
    }
  }
}

TEST(PcdPclParity, KeelRoundTripsAreBitForBit) {
  const PointCloud cloud = random_cloud(3000, 3);
  for (ScanEncoding encoding : kEncodings) {
    SCOPED_TRACE(static_cast<int>(encoding));
    const fs::path path = scratch() / "round.pcd";
    write_pcd(path, cloud, with_time(encoding));
    const PointCloud back = read_pcd(path, cloud.t_ns, read_time());
    ASSERT_EQ(back.size(), cloud.size());
    EXPECT_EQ(std::memcmp(back.xyz.data(), cloud.xyz.data(), cloud.size() * 12), 0);
    EXPECT_EQ(back.intensity, cloud.intensity);
    EXPECT_EQ(back.ring, cloud.ring);
    EXPECT_EQ(back.time_s, cloud.time_s);
  }
}

TEST(Lzf, DecompressInvertsCompressOnRandomRepetitiveAndEmptyData) {
  std::mt19937 rng(4);
  std::vector<std::vector<uint8_t>> inputs(5);
  for (int i = 0; i < 10000; ++i) inputs[0].push_back(static_cast<uint8_t>(rng()));
  inputs[1].assign(70000, 7);
  for (int i = 0; i < 50000; ++i) inputs[2].push_back(static_cast<uint8_t>((i / 3) % 251));
  inputs[3] = {1, 2};
  for (const auto& input : inputs) {
    const std::vector<uint8_t> packed = lzf_compress(input.data(), input.size());
    EXPECT_LE(packed.size(), input.size() + input.size() / 32 + 1);
    const auto back = lzf_decompress(packed.data(), packed.size(), input.size());
    ASSERT_TRUE(back.has_value()) << input.size();
    EXPECT_EQ(*back, input);
  }
  EXPECT_LT(lzf_compress(inputs[1].data(), inputs[1].size()).size(), 70000u / 80);
}

TEST(Lzf, MalformedStreamsAreRefused) {
  const std::vector<uint8_t> literal_past_end = {5, 'a', 'b'};  // 6 literals promised
  EXPECT_FALSE(lzf_decompress(literal_past_end.data(), literal_past_end.size(), 6));
  const std::vector<uint8_t> reference_before_start = {0, 'a', 0x20, 5};  // distance 6 > 1
  EXPECT_FALSE(lzf_decompress(reference_before_start.data(), reference_before_start.size(), 4));
  const std::vector<uint8_t> short_output = {1, 'a', 'b'};
  EXPECT_FALSE(lzf_decompress(short_output.data(), short_output.size(), 3));
  EXPECT_FALSE(lzf_decompress(short_output.data(), short_output.size(), 1));
  const std::vector<uint8_t> back_reference = {0, 'a', 0x20, 0};  // 'a' then 3 x 'a'
  const auto ok = lzf_decompress(back_reference.data(), back_reference.size(), 4);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(*ok, (std::vector<uint8_t>{'a', 'a', 'a', 'a'}));
}

}  // namespace
}  // namespace keel::io
