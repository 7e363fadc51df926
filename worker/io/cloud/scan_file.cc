#include "worker/io/cloud/scan_file.h"

#include <algorithm>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

enum class Format { kPcd, kPly };

Format format_of(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".pcd") return Format::kPcd;
  if (ext == ".ply") return Format::kPly;
  throw IoError(display_path(path) + ": unknown scan format '" + ext + "' (expected .pcd or .ply)");
}

}  // namespace

ScanFileInfo read_scan_info(const fs::path& path) {
  return format_of(path) == Format::kPcd ? read_pcd_info(path) : read_ply_info(path);
}

PointCloud read_scan_file(const fs::path& path, TimeNs t_ns, const ScanReadOptions& options) {
  return format_of(path) == Format::kPcd ? read_pcd(path, t_ns, options)
                                         : read_ply(path, t_ns, options);
}

void write_scan_file(const fs::path& path, const PointCloud& cloud,
                     const ScanWriteOptions& options) {
  if (format_of(path) == Format::kPcd)
    write_pcd(path, cloud, options);
  else
    write_ply(path, cloud, options);
}

}  // namespace keel::io
