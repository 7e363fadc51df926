#include "worker/io/mesh/mesh_ply_binary_writer.h"

#include "core/replaced_file.h"

namespace keel::io::mesh_detail {

void PlyBinaryWriter::begin(const std::string& header_lines, size_t expected_body_bytes) {
  buffer_ = "ply\nformat binary_little_endian 1.0\ncomment written by keel\n" + header_lines +
            "end_header\n";
  buffer_.reserve(buffer_.size() + expected_body_bytes);
}

void PlyBinaryWriter::finish() {
  write_file_replacing(path_, buffer_);
  buffer_.clear();
  buffer_.shrink_to_fit();
}

}  // namespace keel::io::mesh_detail
