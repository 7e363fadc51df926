#include "worker/io/bag/ros1_bag.h"

#include <algorithm>
#include <cstring>
#include <optional>
#include <utility>

#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/ros1_chunk.h"

namespace keel::io {
namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicSize = sizeof(kMagic) - 1;

constexpr int kOpMessageData = 0x02, kOpBagHeader = 0x03, kOpIndexData = 0x04, kOpChunk = 0x05,
              kOpChunkInfo = 0x06, kOpConnection = 0x07;

uint32_t le32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint64_t le64(const uint8_t* p) { return le32(p) | uint64_t(le32(p + 4)) << 32; }

// The header fields Keel uses (format 2.0: op, and per op the fields below).
struct RecordHeader {
  int op = -1;
  std::string compression, topic;      // chunk; connection
  std::optional<uint32_t> size;        // chunk: bytes once uncompressed
  std::optional<uint32_t> ver, count;  // index data
  std::optional<uint32_t> conn;        // connection, index data, message data
  std::optional<uint64_t> time;        // message data: uint32 sec, uint32 nsec
  std::optional<uint64_t> index_pos;   // bag header: first record after the chunks
  std::optional<uint64_t> chunk_pos;   // chunk info: where its chunk starts
  // A connection record's data: the publisher's connection header.
  std::string type, md5sum, message_definition;
};

template <typename T>
T number(const std::string& name, const uint8_t* value, size_t size, const std::string& where) {
  if (size != sizeof(T))
    throw BagFormatError(where + ": header field '" + name + "' has " + std::to_string(size) +
                         " bytes; expected " + std::to_string(sizeof(T)));
  if constexpr (sizeof(T) == 4)
    return le32(value);
  else
    return le64(value);
}

// Reads a header's fields (each inside the header, each with a '='); `out` keeps the ones
// Keel uses.
void read_header(const uint8_t* header, size_t size, const std::string& where, RecordHeader& out) {
  size_t at = 0;
  while (at < size) {
    if (size - at < 4) throw BagFormatError(where + ": a header field's length is cut off");
    const uint32_t length = le32(header + at);
    at += 4;
    if (length > size - at)
      throw BagFormatError(where + ": a header field of " + std::to_string(length) +
                           " bytes runs past its header (" + std::to_string(size - at) +
                           " bytes left)");
    const char* field = reinterpret_cast<const char*>(header + at);
    const char* equals = static_cast<const char*>(std::memchr(field, '=', length));
    if (!equals) throw BagFormatError(where + ": a header field has no '='");
    const std::string name(field, equals);
    const auto* value = reinterpret_cast<const uint8_t*>(equals + 1);
    const size_t value_size = static_cast<size_t>(field + length - (equals + 1));
    const std::string text(equals + 1, field + length);
    if (name == "op") out.op = value_size == 1 ? value[0] : -2;
    if (name == "compression") out.compression = text;
    if (name == "topic") out.topic = text;
    if (name == "type") out.type = text;
    if (name == "md5sum") out.md5sum = text;
    if (name == "message_definition") out.message_definition = text;
    if (name == "size") out.size = number<uint32_t>(name, value, value_size, where);
    if (name == "ver") out.ver = number<uint32_t>(name, value, value_size, where);
    if (name == "count") out.count = number<uint32_t>(name, value, value_size, where);
    if (name == "conn") out.conn = number<uint32_t>(name, value, value_size, where);
    if (name == "time") out.time = number<uint64_t>(name, value, value_size, where);
    if (name == "index_pos") out.index_pos = number<uint64_t>(name, value, value_size, where);
    if (name == "chunk_pos") out.chunk_pos = number<uint64_t>(name, value, value_size, where);
    at += length;
  }
}

// ROS1 time (uint32 sec, uint32 nsec, as rosbag stores it) in ns.
TimeNs time_ns(uint64_t time) {
  return static_cast<TimeNs>(time & 0xffffffffu) * 1000000000 + static_cast<TimeNs>(time >> 32);
}

// One record of a chunk's uncompressed data at `at`, every length checked.
struct ChunkRecord {
  RecordHeader header;
  size_t data_at = 0, data_size = 0;
};
ChunkRecord chunk_record(const std::vector<uint8_t>& data, size_t at, const std::string& where) {
  if (at > data.size() || data.size() - at < 8) throw BagFormatError(where + ": cut off");
  const uint32_t header_length = le32(data.data() + at);
  if (header_length > data.size() - at - 8)
    throw BagFormatError(where + ": header of " + std::to_string(header_length) +
                         " bytes runs past its chunk");
  ChunkRecord r;
  read_header(data.data() + at + 4, header_length, where, r.header);
  r.data_at = at + 4 + header_length;
  r.data_size = le32(data.data() + r.data_at);
  r.data_at += 4;
  if (r.data_size > data.size() - r.data_at)
    throw BagFormatError(where + ": data of " + std::to_string(r.data_size) +
                         " bytes runs past its chunk");
  return r;
}

// Checks the records of a chunk's uncompressed data; returns the offset each starts at (index
// entries must point at one of them).
std::vector<uint32_t> check_records(const std::vector<uint8_t>& data,
                                    const std::string& chunk_where) {
  std::vector<uint32_t> starts;
  for (size_t at = 0; at < data.size();) {
    const std::string where =
        chunk_where + ", record at byte " + std::to_string(at) + " of its uncompressed data";
    const ChunkRecord r = chunk_record(data, at, where);
    if (r.header.op == kOpConnection) {
      RecordHeader connection;
      read_header(data.data() + r.data_at, r.data_size, where + " (its connection header)",
                  connection);
    }
    starts.push_back(static_cast<uint32_t>(at));
    at = r.data_at + r.data_size;
  }
  return starts;
}

}  // namespace

Ros1Bag::Ros1Bag(std::shared_ptr<const ByteSource> bytes, std::string name)
    : bytes_(std::move(bytes)), name_(std::move(name)) {
  const uint64_t size = bytes_->size();
  uint8_t magic[kMagicSize] = {};
  if (size >= kMagicSize) bytes_->read(0, kMagicSize, magic);
  if (std::memcmp(magic, kMagic, kMagicSize) != 0)
    throw BagFormatError(name_ + ": not a ROS bag 2.0 (no '#ROSBAG V2.0' line)");
  const std::string corrupt = name_ + ": truncated or corrupt bag: ";
  std::vector<uint64_t> record_starts, chunk_starts;
  std::vector<std::pair<uint64_t, std::string>> index_pos, chunk_pos;  // (position, where)
  std::optional<uint64_t> bag_index_pos;
  std::optional<std::vector<uint32_t>> chunk_records;  // of the last chunk
  // In file order; their topics are known once the index section is read.
  std::vector<Ros1IndexEntry> entries;
  std::vector<uint8_t> header, data, records;
  uint64_t at = kMagicSize;
  while (at < size) {
    const std::string where = corrupt + "record at byte " + std::to_string(at);
    uint8_t length[4];
    if (size - at < 8) throw BagFormatError(where + ": cut off");
    bytes_->read(at, 4, length);
    const uint32_t header_length = le32(length);
    if (header_length > size - at - 8)
      throw BagFormatError(where + ": header of " + std::to_string(header_length) +
                           " bytes runs past the end of the file");
    header.resize(header_length);
    bytes_->read(at + 4, header_length, header.data());
    RecordHeader h;
    read_header(header.data(), header.size(), where, h);
    bytes_->read(at + 4 + header_length, 4, length);
    const uint32_t data_length = le32(length);
    const uint64_t data_at = at + 8 + header_length;
    if (data_length > size - data_at)
      throw BagFormatError(where + ": data of " + std::to_string(data_length) +
                           " bytes runs past the end of the file");
    record_starts.push_back(at);
    if (h.op == kOpChunk || h.op == kOpIndexData || h.op == kOpConnection) {
      data.resize(data_length);
      bytes_->read(data_at, data_length, data.data());
    }
    if (h.op == kOpChunk) {
      if (!h.size) throw BagFormatError(where + ": chunk without a 'size' field");
      decompress_ros1_chunk(h.compression, data, *h.size, where, records);
      chunk_records = check_records(records, where + " (a chunk)");
      Ros1Chunk chunk;
      chunk.data_at = data_at;
      chunk.stored_size = data_length;
      chunk.size = *h.size;
      chunk.compression = h.compression == "bz2"   ? Ros1Compression::kBz2
                          : h.compression == "lz4" ? Ros1Compression::kLz4
                                                   : Ros1Compression::kNone;
      chunk_starts.push_back(at);
      chunks_.push_back(chunk);
    } else if (h.op == kOpIndexData) {
      // Entries (uint32 sec, uint32 nsec, uint32 offset) of the chunk before it.
      if (!chunk_records) throw BagFormatError(where + ": index data before any chunk");
      if (h.ver != 1u) throw BagFormatError(where + ": index data version is not 1");
      if (!h.conn) throw BagFormatError(where + ": index data without a 'conn' field");
      if (!h.count || data.size() != uint64_t(*h.count) * 12)
        throw BagFormatError(
            where + ": index data of " + std::to_string(data.size()) + " bytes does not hold " +
            (h.count ? std::to_string(*h.count) : std::string("its")) + " entries of 12 bytes");
      for (uint32_t i = 0; i < *h.count; ++i) {
        Ros1IndexEntry e;
        e.time_ns = time_ns(le64(data.data() + 12 * i));
        e.chunk = static_cast<uint32_t>(chunks_.size() - 1);
        e.offset = le32(data.data() + 12 * i + 8);
        e.conn = *h.conn;
        if (!std::binary_search(chunk_records->begin(), chunk_records->end(), e.offset))
          throw BagFormatError(where + ": index entry " + std::to_string(i) + " points at byte " +
                               std::to_string(e.offset) + " of its chunk, where no record starts");
        entries.push_back(e);
      }
    } else if (h.op == kOpConnection) {
      // Its data is the publisher's connection header, in the same field format; the topic is
      // the record's (rosbag's, which may be remapped).
      RecordHeader c;
      read_header(data.data(), data.size(), where + " (its connection header)", c);
      if (!h.conn) throw BagFormatError(where + ": connection without a 'conn' field");
      connections_[*h.conn] = {*h.conn, h.topic, c.type, c.md5sum, c.message_definition};
    } else if (h.op == kOpBagHeader) {
      // An index_pos of 0 is a bag whose recording did not finish (no index section).
      if (!h.index_pos) throw BagFormatError(where + ": bag header without 'index_pos'");
      bag_index_pos = *h.index_pos;
      if (*h.index_pos != 0) index_pos.emplace_back(*h.index_pos, where);
    } else if (h.op == kOpChunkInfo && h.chunk_pos) {
      chunk_pos.emplace_back(*h.chunk_pos, where);
    }
    at = data_at + data_length;
  }
  if (!bag_index_pos) throw BagFormatError(corrupt + "no bag header record");
  if (*bag_index_pos == 0)
    throw BagFormatError(name_ +
                         ": the bag is unindexed (its recording did not finish?); "
                         "`rosbag reindex` writes its index");
  // The positions rosbag seeks to must hold a record (a chunk).
  for (const auto& [position, where] : index_pos)
    if (!std::binary_search(record_starts.begin(), record_starts.end(), position))
      throw BagFormatError(where + ": index_pos " + std::to_string(position) +
                           " is not the start of a record");
  for (const auto& [position, where] : chunk_pos)
    if (!std::binary_search(chunk_starts.begin(), chunk_starts.end(), position))
      throw BagFormatError(where + ": chunk_pos " + std::to_string(position) +
                           " is not the start of a chunk");
  for (const Ros1IndexEntry& entry : entries) {
    const auto c = connections_.find(entry.conn);
    if (c == connections_.end())
      throw BagFormatError(corrupt + "index data of connection " + std::to_string(entry.conn) +
                           ", which no connection record declares");
    entries_[c->second.topic].push_back(entry);
  }
  // rosbag's View: by time, equal times in index order.
  for (auto& [topic, list] : entries_)
    std::stable_sort(
        list.begin(), list.end(),
        [](const Ros1IndexEntry& a, const Ros1IndexEntry& b) { return a.time_ns < b.time_ns; });
}

Ros1Bag::~Ros1Bag() = default;

size_t Ros1Bag::message_count(const std::string& topic) const {
  const auto it = entries_.find(topic);
  return it == entries_.end() ? 0 : it->second.size();
}

void Ros1Bag::read_chunk(const Ros1Chunk& chunk, const std::string& where,
                         std::vector<uint8_t>& out) const {
  std::vector<uint8_t> stored(chunk.stored_size);
  bytes_->read(chunk.data_at, stored.size(), stored.data());
  static const char* const kNames[] = {"none", "bz2", "lz4"};
  decompress_ros1_chunk(kNames[static_cast<int>(chunk.compression)], stored, chunk.size, where,
                        out);
}

Ros1Bag::Cursor::Cursor(const Ros1Bag& bag, const std::string& topic) : bag_(&bag) {
  const auto it = bag.entries_.find(topic);
  if (it != bag.entries_.end()) entries_ = &it->second;
}

bool Ros1Bag::Cursor::next(Ros1Message& message) {
  if (!entries_ || next_ == entries_->size()) return false;
  const Ros1IndexEntry& e = (*entries_)[next_];
  const Ros1Chunk& chunk = bag_->chunks_[e.chunk];
  const std::string where = "chunk at byte " + std::to_string(chunk.data_at) + " of the file";
  if (loaded_chunk_ != e.chunk) {
    loaded_chunk_ = UINT32_MAX;
    bag_->read_chunk(chunk, where, chunk_);
    loaded_chunk_ = e.chunk;
  }
  const std::string record_where = where + ", record at byte " + std::to_string(e.offset);
  const ChunkRecord r = chunk_record(chunk_, e.offset, record_where);
  if (r.header.op != kOpMessageData)
    throw BagFormatError(record_where + ": the index points at a record of op " +
                         std::to_string(r.header.op) + ", not a message (op 2)");
  if (r.header.conn != e.conn)
    throw BagFormatError(record_where + ": a message of another connection than its index's");
  message.connection = &bag_->connections_.at(e.conn);  // checked when opened
  message.time_ns = e.time_ns;
  message.data = chunk_.data() + r.data_at;
  message.size = r.data_size;
  ++next_;
  return true;
}

}  // namespace keel::io
