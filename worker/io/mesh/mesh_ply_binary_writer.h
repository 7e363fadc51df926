// Internal to the PLY writers: a binary_little_endian body built in memory and written
// through a temporary file, so a failed write never leaves a half-written PLY behind.
#pragma once

#include <cstring>
#include <filesystem>
#include <string>

namespace keel::io::mesh_detail {

class PlyBinaryWriter {
 public:
  explicit PlyBinaryWriter(std::filesystem::path path) : path_(std::move(path)) {}

  // `header` holds the lines between "format ..." and "end_header" (element/property lines).
  void begin(const std::string& header_lines, size_t expected_body_bytes);
  template <typename T>
  void put(T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));  // little endian, as are Keel's hosts
    buffer_.append(bytes, sizeof(T));
  }
  // Writes the file; throws std::runtime_error naming it on failure.
  void finish();

 private:
  std::filesystem::path path_;
  std::string buffer_;
};

}  // namespace keel::io::mesh_detail
