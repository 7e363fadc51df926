#include "worker/io/bag/bag_record_check.h"

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "worker/io/display_path.h"
#include "worker/io/io_error.h"

namespace keel::io {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;
// rosbag writes chunks of 768 KiB by default; a chunk declaring more than this is refused
// rather than allocated (rosbag allocates what the header says).
constexpr uint32_t kMaxChunkBytes = 1u << 30;

constexpr int kOpIndexData = 0x04, kOpChunk = 0x05, kOpChunkInfo = 0x06, kOpBagHeader = 0x03,
              kOpConnection = 0x07;

uint32_t le32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint64_t le64(const unsigned char* p) { return le32(p) | uint64_t(le32(p + 4)) << 32; }

// The header fields the checks use (format 2.0: op, and per op the fields below).
struct RecordHeader {
  int op = -1;
  std::string compression;             // chunk
  std::optional<uint32_t> size;        // chunk: bytes once uncompressed
  std::optional<uint32_t> ver, count;  // index data
  std::optional<uint64_t> index_pos;   // bag header: first record after the chunks
  std::optional<uint64_t> chunk_pos;   // chunk info: where its chunk starts
};

template <typename T>
T number(const std::string& name, const std::string& value, const std::string& where) {
  if (value.size() != sizeof(T))
    throw IoError(where + ": header field '" + name + "' has " + std::to_string(value.size()) +
                  " bytes; expected " + std::to_string(sizeof(T)));
  const auto* p = reinterpret_cast<const unsigned char*>(value.data());
  if constexpr (sizeof(T) == 4)
    return le32(p);
  else
    return le64(p);
}

// Checks one record header's fields (each inside the header, each with a '=') and reads the
// ones the checks use.
RecordHeader read_header(const std::vector<unsigned char>& header, const std::string& where) {
  RecordHeader out;
  size_t at = 0;
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
    if (name == "op") out.op = value.size() == 1 ? static_cast<unsigned char>(value[0]) : -2;
    if (name == "compression") out.compression = value;
    if (name == "size") out.size = number<uint32_t>(name, value, where);
    if (name == "ver") out.ver = number<uint32_t>(name, value, where);
    if (name == "count") out.count = number<uint32_t>(name, value, where);
    if (name == "index_pos") out.index_pos = number<uint64_t>(name, value, where);
    if (name == "chunk_pos") out.chunk_pos = number<uint64_t>(name, value, where);
    at += length;
  }
  return out;
}

// Checks the records of a chunk's uncompressed data and returns the offset each starts at
// (index entries must point at one of them: rosbag reads a record wherever they point).
std::vector<uint32_t> check_records(const std::vector<unsigned char>& data,
                                    const std::string& chunk_where) {
  std::vector<uint32_t> starts;
  size_t at = 0;
  while (at < data.size()) {
    const std::string where =
        chunk_where + ", record at byte " + std::to_string(at) + " of its uncompressed data";
    if (data.size() - at < 8) throw IoError(where + ": cut off");
    const uint32_t header_length = le32(data.data() + at);
    if (header_length > data.size() - at - 8)
      throw IoError(where + ": header of " + std::to_string(header_length) +
                    " bytes runs past its chunk");
    const std::vector<unsigned char> header(data.begin() + at + 4,
                                            data.begin() + at + 4 + header_length);
    const RecordHeader h = read_header(header, where);
    const size_t data_at = at + 4 + header_length;
    const uint32_t data_length = le32(data.data() + data_at);
    if (data_length > data.size() - data_at - 4)
      throw IoError(where + ": data of " + std::to_string(data_length) +
                    " bytes runs past its chunk");
    if (h.op == kOpConnection)
      (void)read_header({data.begin() + data_at + 4, data.begin() + data_at + 4 + data_length},
                        where + " (its connection header)");
    starts.push_back(static_cast<uint32_t>(at));
    at = data_at + 4 + data_length;
  }
  return starts;
}

// A chunk's records as rosbag will read them: stored, or decompressed as rosbag does (bz2,
// or roslz4's frames), and exactly as long as its `size` field says.
std::vector<unsigned char> chunk_data(const RecordHeader& h, std::vector<unsigned char> stored,
                                      const std::string& where) {
  if (!h.size) throw IoError(where + ": chunk without a 'size' field");
  const uint32_t size = *h.size;
  if (size > kMaxChunkBytes)
    throw IoError(where + ": chunk declares " + std::to_string(size) +
                  " bytes uncompressed; Keel reads chunks of up to " +
                  std::to_string(kMaxChunkBytes) + " bytes");
  std::vector<unsigned char> data;
  unsigned int produced = size;
  if (h.compression == "none") {
    data = std::move(stored);
    produced = static_cast<unsigned int>(data.size());
  } else if (h.compression == "lz4") {
    data.resize(size);
    const int rc = roslz4_buffToBuffDecompress(reinterpret_cast<char*>(stored.data()),
                                               static_cast<unsigned int>(stored.size()),
                                               reinterpret_cast<char*>(data.data()), &produced);
    if (rc < 0)
      throw IoError(where + ": lz4 chunk does not decompress (roslz4 error " + std::to_string(rc) +
                    ")");
  } else if (h.compression == "bz2") {
    data.resize(size);
    const int rc = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(data.data()), &produced,
                                              reinterpret_cast<char*>(stored.data()),
                                              static_cast<unsigned int>(stored.size()), 0, 0);
    if (rc != BZ_OK)
      throw IoError(where + ": bz2 chunk does not decompress (bzip2 error " + std::to_string(rc) +
                    ")");
  } else {
    throw IoError(where + ": chunk compression '" + h.compression +
                  "' (expected none, lz4 or bz2)");
  }
  if (produced != size)
    throw IoError(where + ": chunk holds " + std::to_string(produced) +
                  " bytes uncompressed; its " + "'size' field says " + std::to_string(size));
  return data;
}

// An index data record's entries (uint64 time, uint32 offset) must each point at a record of
// the chunk before it.
void check_index(const RecordHeader& h, const std::vector<unsigned char>& data,
                 const std::vector<uint32_t>* chunk_records, const std::string& where) {
  if (chunk_records == nullptr) throw IoError(where + ": index data before any chunk");
  if (h.ver != 1u) throw IoError(where + ": index data version is not 1");
  if (!h.count || data.size() != uint64_t(*h.count) * 12)
    throw IoError(
        where + ": index data of " + std::to_string(data.size()) + " bytes does not hold " +
        (h.count ? std::to_string(*h.count) : std::string("its")) + " entries of 12 bytes");
  for (uint32_t i = 0; i < *h.count; ++i) {
    const uint32_t offset = le32(data.data() + 12 * i + 8);
    if (!std::binary_search(chunk_records->begin(), chunk_records->end(), offset))
      throw IoError(where + ": index entry " + std::to_string(i) + " points at byte " +
                    std::to_string(offset) + " of its chunk, where no record starts");
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
  const std::string corrupt = name + ": truncated or corrupt bag: ";
  std::vector<uint64_t> record_starts, chunk_starts;
  std::vector<std::pair<uint64_t, std::string>> index_pos, chunk_pos;  // (position, where)
  std::optional<std::vector<uint32_t>> chunk_records;                  // of the last chunk
  uint64_t at = kMagicSize;
  while (at < size) {
    const std::string where = corrupt + "record at byte " + std::to_string(at);
    unsigned char length[4];
    if (size - at < 8 || !in.read(reinterpret_cast<char*>(length), 4))
      throw IoError(where + ": cut off");
    const uint32_t header_length = le32(length);
    if (header_length > size - at - 8)
      throw IoError(where + ": header of " + std::to_string(header_length) +
                    " bytes runs past the end of the file");
    std::vector<unsigned char> header(header_length);
    in.read(reinterpret_cast<char*>(header.data()), header_length);
    const RecordHeader h = read_header(header, where);
    if (!in.read(reinterpret_cast<char*>(length), 4)) throw IoError(where + ": cut off");
    const uint32_t data_length = le32(length);
    const uint64_t data_at = at + 8 + header_length;
    if (data_length > size - data_at)
      throw IoError(where + ": data of " + std::to_string(data_length) +
                    " bytes runs past the end of the file");
    record_starts.push_back(at);
    if (h.op == kOpChunk || h.op == kOpIndexData || h.op == kOpConnection) {
      std::vector<unsigned char> data(data_length);
      in.read(reinterpret_cast<char*>(data.data()), data_length);
      if (h.op == kOpChunk) {
        chunk_starts.push_back(at);
        chunk_records = check_records(chunk_data(h, std::move(data), where), where + " (a chunk)");
      } else if (h.op == kOpIndexData) {
        check_index(h, data, chunk_records ? &*chunk_records : nullptr, where);
      } else {  // its data is the publisher's connection header, in the same field format
        (void)read_header(data, where + " (its connection header)");
      }
    } else {
      in.seekg(static_cast<std::streamoff>(data_length), std::ios::cur);
    }
    // An index_pos of 0 is an unindexed bag, which rosbag refuses naming it.
    if (h.op == kOpBagHeader && h.index_pos && *h.index_pos != 0)
      index_pos.emplace_back(*h.index_pos, where);
    if (h.op == kOpChunkInfo && h.chunk_pos) chunk_pos.emplace_back(*h.chunk_pos, where);
    at = data_at + data_length;
  }
  // rosbag seeks to these positions and reads a record there.
  for (const auto& [position, where] : index_pos)
    if (!std::binary_search(record_starts.begin(), record_starts.end(), position))
      throw IoError(where + ": index_pos " + std::to_string(position) +
                    " is not the start of a record");
  for (const auto& [position, where] : chunk_pos)
    if (!std::binary_search(chunk_starts.begin(), chunk_starts.end(), position))
      throw IoError(where + ": chunk_pos " + std::to_string(position) +
                    " is not the start of a chunk");
}

}  // namespace keel::io
