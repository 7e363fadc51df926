// Scans one at a time, whatever the source (a folder of PCD/PLY files or a bag topic of
// sensor_msgs/PointCloud2): a reader never holds more than one scan.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "worker/io/folder_index.h"
#include "worker/io/cloud/packed_cloud.h"

namespace keel::io {

class ScanSource {
 public:
  virtual ~ScanSource() = default;
  // Number of scans (known up front from index.csv or the bag index).
  virtual size_t size() const = 0;
  // Reads the next scan into `cloud`, replacing its contents; false after the last one.
  virtual bool next(PointCloud& cloud) = 0;
  // The file or bag message of the scan last returned (for messages).
  virtual std::string current_source() const = 0;
};

// A scan folder: index.csv plus one PCD/PLY file per scan.
class ScanFolderReader : public ScanSource {
 public:
  ScanFolderReader(const std::filesystem::path& folder, ScanReadOptions options);
  size_t size() const override { return entries_.size(); }
  bool next(PointCloud& cloud) override;
  std::string current_source() const override;
  const std::vector<IndexEntry>& entries() const { return entries_; }

 private:
  std::vector<IndexEntry> entries_;
  ScanReadOptions options_;
  size_t next_ = 0;
};

}  // namespace keel::io
