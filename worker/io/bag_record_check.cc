#include "worker/io/bag_record_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;

uint32_t le32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// Checks one record header's fields; returns true when it is an uncompressed chunk
// (op=0x05, compression=none), whose data holds records of its own.
bool check_header(const std::vector<unsigned char>& header, const std::string& where) {
  size_t at = 0;
  bool chunk = false, uncompressed = false;
  while (at < header.size()) {
    if (header.size() - at < 4) throw IoError(where + ": a header field's length is cut off");
    const uint32_t length = le32(header.data() + at);
    at += 4;
    if (length > header.size() - at)
      throw IoError(where + ": a header field of " + std::to_string(length) +
                    " bytes runs past its header (" + std::to_string(header.size() - at) +
                    " bytes left)");
    const char* field = reinterpret_cast<const char*>(header.data() + at);
    const void* equals = std::memchr(field, '=', length);
    if (!equals) throw IoError(where + ": a header field has no '='");
    const std::string name(field, static_cast<const char*>(equals));
    const std::string value(static_cast<const char*>(equals) + 1, field + length);
    if (name == "op") chunk = value.size() == 1 && value[0] == 0x05;
    if (name == "compression") uncompressed = value == "none";
    at += length;
  }
  return chunk && uncompressed;
}

// The records of an uncompressed chunk's data, which starts at byte `file_offset` of the bag.
void check_records(const std::vector<unsigned char>& data, const std::string& name,
                   uint64_t file_offset) {
  size_t at = 0;
  while (at < data.size()) {
    const std::string where =
        name + ": truncated or corrupt bag: record at byte " + std::to_string(file_offset + at);
    if (data.size() - at < 8) throw IoError(where + ": cut off");
    const uint32_t header_length = le32(data.data() + at);
    if (header_length > data.size() - at - 8)
      throw IoError(where + ": header of " + std::to_string(header_length) +
                    " bytes runs past its chunk");
    const std::vector<unsigned char> header(data.begin() + at + 4,
                                            data.begin() + at + 4 + header_length);
    check_header(header, where);
    const size_t data_at = at + 4 + header_length;
    const uint32_t data_length = le32(data.data() + data_at);
    if (data_length > data.size() - data_at - 4)
      throw IoError(where + ": data of " + std::to_string(data_length) +
                    " bytes runs past its chunk");
    at = data_at + 4 + data_length;
  }
}

}  // namespace

void check_bag_records(const std::filesystem::path& path) {
  const std::string name = display_path(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(name + ": cannot open bag");
  in.seekg(0, std::ios::end);
  const uint64_t size = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  char magic[kMagicSize] = {};
  if (!in.read(magic, kMagicSize) || std::memcmp(magic, kMagic, kMagicSize) != 0)
    throw IoError(name + ": not a ROS bag 2.0 (no '#ROSBAG V2.0' line)");
  uint64_t at = kMagicSize;
  while (at < size) {
    const std::string where =
        name + ": truncated or corrupt bag: record at byte " + std::to_string(at);
    unsigned char length[4];
    if (size - at < 8 || !in.read(reinterpret_cast<char*>(length), 4))
      throw IoError(where + ": cut off");
    const uint32_t header_length = le32(length);
    if (header_length > size - at - 8)
      throw IoError(where + ": header of " + std::to_string(header_length) +
                    " bytes runs past the end of the file");
    std::vector<unsigned char> header(header_length);
    in.read(reinterpret_cast<char*>(header.data()), header_length);
    const bool uncompressed_chunk = check_header(header, where);
    if (!in.read(reinterpret_cast<char*>(length), 4)) throw IoError(where + ": cut off");
    const uint32_t data_length = le32(length);
    const uint64_t data_at = at + 8 + header_length;
    if (data_length > size - data_at)
      throw IoError(where + ": data of " + std::to_string(data_length) +
                    " bytes runs past the end of the file");
    if (uncompressed_chunk) {
      std::vector<unsigned char> data(data_length);
      in.read(reinterpret_cast<char*>(data.data()), data_length);
      check_records(data, name, data_at);
    } else {
      in.seekg(static_cast<std::streamoff>(data_length), std::ios::cur);
    }
    at = data_at + data_length;
  }
}

}  // namespace keel::io
