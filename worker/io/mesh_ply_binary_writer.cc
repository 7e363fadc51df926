#include "worker/io/mesh_ply_binary_writer.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace keel::io::mesh_detail {

void PlyBinaryWriter::begin(const std::string& header_lines, size_t expected_body_bytes) {
  buffer_ = "ply\nformat binary_little_endian 1.0\ncomment written by keel\n" + header_lines +
            "end_header\n";
  buffer_.reserve(buffer_.size() + expected_body_bytes);
}

void PlyBinaryWriter::finish() {
  std::filesystem::path temporary = path_;
  temporary += ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error(path_.string() + ": cannot open for writing (" +
                               std::strerror(errno) + ")");
    out.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw std::runtime_error(path_.string() + ": write failed (disk full?)");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path_, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw std::runtime_error(path_.string() +
                             ": cannot move the written file into place: " + error.message());
  }
  buffer_.clear();
  buffer_.shrink_to_fit();
}

}  // namespace keel::io::mesh_detail
