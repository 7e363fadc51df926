// `index.csv` of a scan or image folder: header `t,file`, strictly increasing stamps, files
// relative to the folder (docs/mission-format.md "Scan and image folders").
#pragma once

#include <filesystem>
#include <vector>

#include "core/time.h"

namespace keel::io {

struct IndexEntry {
  TimeNs t_ns = 0;
  std::filesystem::path path;  // absolute
  size_t line = 0;             // in index.csv, for messages
};

// Fails naming index.csv and the line for a bad header, stamp, duplicate or decreasing
// stamp, a path leaving the folder, or a file that does not exist.
std::vector<IndexEntry> read_folder_index(const std::filesystem::path& folder);
void write_folder_index(const std::filesystem::path& folder,
                        const std::vector<IndexEntry>& entries);

}  // namespace keel::io
