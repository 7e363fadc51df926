#include "worker/io/scan_source.h"

#include "worker/io/display_path.h"
#include "worker/io/cloud/scan_file.h"

namespace keel::io {

ScanFolderReader::ScanFolderReader(const std::filesystem::path& folder, ScanReadOptions options)
    : entries_(read_folder_index(folder)), options_(std::move(options)) {}

bool ScanFolderReader::next(PointCloud& cloud) {
  if (next_ >= entries_.size()) return false;
  const IndexEntry& entry = entries_[next_++];
  cloud = read_scan_file(entry.path, entry.t_ns, options_);
  return true;
}

std::string ScanFolderReader::current_source() const {
  return next_ == 0 ? std::string() : display_path(entries_[next_ - 1].path);
}

}  // namespace keel::io
