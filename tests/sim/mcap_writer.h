// Writes an MCAP file per the published specification (mcap.dev/spec): magic, Header
// (profile "ros2"), Schema/Channel/Message records in Chunks (zstd, lz4 or uncompressed, each
// with its CRC and its Message Index records), Data End with the data-section CRC, a summary
// (Schemas, Channels, Statistics with per-channel counts, Chunk Indexes) with Summary Offsets,
// and the Footer with the summary CRC. No Debian package writes MCAP.
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace keel::sim {

struct McapWriterOptions {
  std::string compression = "zstd";   // zstd | lz4 | "" (none)
  uint64_t chunk_bytes = 768 * 1024;  // uncompressed records per chunk (the mcap library's default)
};

class McapWriter {
 public:
  McapWriter(const std::string& path, McapWriterOptions options = {});  // throws naming the path
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A ROS 2 type (name "sensor_msgs/msg/Imu", encoding "ros2msg", data its .msg text).
  uint16_t add_schema(const std::string& name, const std::string& encoding,
                      const std::string& data);
  uint16_t add_channel(const std::string& topic, uint16_t schema_id,
                       const std::string& message_encoding = "cdr");
  void write(uint16_t channel_id, uint64_t log_time_ns, const std::vector<uint8_t>& data);
  // Bytes written so far (for splitting a bag by size).
  uint64_t bytes_written() const { return offset_; }
  void close();

 private:
  struct ChunkIndex {
    uint64_t start_time, end_time, offset, length, index_length, compressed, uncompressed;
    std::map<uint16_t, uint64_t> index_offsets;
  };
  void flush_chunk();
  void emit(const std::vector<uint8_t>& bytes);

  std::string path_;
  McapWriterOptions options_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;  // CRC of every byte written so far (the data section's)
  std::vector<std::vector<uint8_t>> schema_records_, channel_records_;
  std::map<uint16_t, uint64_t> channel_counts_;
  uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0;
  // The open chunk: its records, and per channel (log time, offset in the records).
  std::vector<uint8_t> chunk_;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_has_messages_ = false;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<uint32_t> sequence_;  // per channel
};

}  // namespace keel::sim
