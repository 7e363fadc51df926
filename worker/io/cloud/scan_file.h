// One scan file (PCD: ascii, binary, binary_compressed; PLY: ascii, binary_little_endian)
// read into a keel::PointCloud, or written from one. The format follows the extension.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/cloud/packed_cloud.h"

namespace keel::io {

enum class ScanEncoding { kAscii, kBinary, kBinaryCompressed };  // compressed: PCD only

struct ScanWriteOptions {
  ScanEncoding encoding = ScanEncoding::kBinary;
  std::optional<PointTimeEncoding> time;  // none: no time field written
};

struct ScanFileInfo {
  size_t num_points = 0;
  std::vector<PackedField> fields;
  std::string format;  // "pcd ascii", "pcd binary", "pcd binary_compressed", "ply ascii", ...
};

// Header only (cheap): point count and fields. Fails naming the file on a malformed header.
ScanFileInfo read_scan_info(const std::filesystem::path& path);
// The whole scan; `t_ns` is its stamp (from index.csv). Truncated or malformed files fail
// naming the file and what was expected.
PointCloud read_scan_file(const std::filesystem::path& path, TimeNs t_ns,
                          const ScanReadOptions& options = {});
void write_scan_file(const std::filesystem::path& path, const PointCloud& cloud,
                     const ScanWriteOptions& options = {});

// Per format (read_scan_file dispatches on the extension).
ScanFileInfo read_pcd_info(const std::filesystem::path& path);
PointCloud read_pcd(const std::filesystem::path& path, TimeNs t_ns, const ScanReadOptions& options);
void write_pcd(const std::filesystem::path& path, const PointCloud& cloud,
               const ScanWriteOptions& options);
ScanFileInfo read_ply_info(const std::filesystem::path& path);
PointCloud read_ply(const std::filesystem::path& path, TimeNs t_ns, const ScanReadOptions& options);
void write_ply(const std::filesystem::path& path, const PointCloud& cloud,
               const ScanWriteOptions& options);

}  // namespace keel::io
