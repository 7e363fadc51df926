// A rosbag2 folder's metadata.yaml (rosbag2_storage's `rosbag2_bagfile_information`,
// versions 1 to 9): the storage, the split files in order, compression and the topics with
// their message counts.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace keel::io {

struct Rosbag2TopicMetadata {
  std::string name;
  std::string type;
  std::string serialization_format;
  uint64_t message_count = 0;
};

struct Rosbag2Metadata {
  int version = 0;
  std::string storage_identifier;                // mcap | sqlite3
  std::vector<std::string> relative_file_paths;  // split files, in recording order
  std::string compression_format;                // "" | zstd
  std::string compression_mode;                  // "" | NONE | MESSAGE | FILE
  uint64_t message_count = 0;
  std::vector<Rosbag2TopicMetadata> topics;
};

// Fails (IoError) naming the file and the key on a missing or malformed key, a file path that
// leaves the folder, or an unknown storage.
Rosbag2Metadata read_rosbag2_metadata(const std::filesystem::path& metadata_yaml);

}  // namespace keel::io
