// MCAP files (the ROS 2 bag storage since Iron), read per the published specification
// (mcap.dev/spec, major version 0): magic, Header, the data section's records (Schema,
// Channel, Message, Chunk compressed with zstd or lz4 or not at all, Message Index,
// Attachment, Metadata, Data End), the optional summary (Schema, Channel, Chunk Index,
// Statistics) and the Footer. No Debian package reads MCAP; zstd and lz4 come from Debian.
//
// Memory stays bounded: a cursor holds one chunk (compressed and uncompressed) at a time.
// Every length is checked against the bytes that hold it. Chunk CRCs and the summary CRC are
// verified when the writer stored them (non-zero). Errors are BagFormatError naming the
// record and its byte offset; the bag reader adds the file, topic and message index.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "worker/io/bag/byte_source.h"

namespace keel::io {

struct McapChannel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // "cdr" for ROS 2
  std::string schema_name;       // the message type, e.g. sensor_msgs/msg/Imu; "" without schema
  uint64_t messages = 0;
};

struct McapMessage {
  const McapChannel* channel = nullptr;
  uint32_t sequence = 0;
  uint64_t log_time = 0;  // ns
  uint64_t publish_time = 0;
  const uint8_t* data = nullptr;  // valid until the cursor moves on
  size_t size = 0;
};

struct McapReadOptions {
  // Refuse records larger than this before allocating for them (a hostile length field
  // must not allocate gigabytes). rosbag2 writes chunks of ~768 KiB; a raw 4K image is 25 MB.
  uint64_t max_record_bytes = 1ull << 30;
};

class McapReader {
 public:
  // Checks the leading magic and the Header; reads the summary through the Footer when the
  // file has one, else (a recording cut short, or a writer that keeps no summary) scans the
  // data section once for channels and message counts. A file cut short opens: its cursors
  // fail where the cut is.
  explicit McapReader(std::shared_ptr<const ByteSource> bytes, McapReadOptions options = {});

  const std::map<uint16_t, McapChannel>& channels() const { return channels_; }
  const std::string& profile() const { return profile_; }  // "ros2" for rosbag2 files
  bool has_summary() const { return has_summary_; }
  // False when the file ends without Footer and closing magic (cut short).
  bool complete() const { return complete_; }

  // Messages of the given channels (all when empty) in file order.
  class Cursor {
   public:
    bool next(McapMessage& message);
    // Byte offset of the record the cursor is in (for messages).
    uint64_t offset() const { return record_offset_; }

   private:
    friend class McapReader;
    Cursor(McapReader* reader, std::set<uint16_t> wanted, bool scanning);
    bool next_in_chunk(McapMessage& message);
    void load_chunk(uint64_t offset, uint64_t length);
    bool wants(uint16_t channel) const;
    bool chunk_has_wanted(uint64_t offset) const;

    McapReader* reader_;
    std::set<uint16_t> wanted_;
    bool scanning_;  // registers schemas and channels, counts messages (opening without summary)
    uint64_t position_;
    uint64_t record_offset_ = 0;
    bool done_ = false;
    std::vector<uint8_t> record_;  // the current chunk's compressed records or a lone record
    std::vector<uint8_t> chunk_;   // the current chunk's records, uncompressed
    size_t chunk_position_ = 0;
    bool in_chunk_ = false;
    std::shared_ptr<void> zstd_, lz4_;  // decompression contexts, reused chunk to chunk
  };
  Cursor messages(std::set<uint16_t> channel_ids = {}) const;

 private:
  void read_footer_and_summary();
  void parse_summary(const std::vector<uint8_t>& summary, uint64_t summary_start);
  void scan_data_section();
  void add_schema(const uint8_t* content, uint64_t size, uint64_t offset);
  void add_channel(const uint8_t* content, uint64_t size, uint64_t offset);
  void resolve_schema_names();

  std::shared_ptr<const ByteSource> bytes_;
  McapReadOptions options_;
  std::string profile_;
  uint64_t data_start_ = 0;  // first record after the Header
  uint64_t data_end_ = 0;    // where the data section's records stop (summary or footer)
  bool complete_ = false;    // trailing magic and Footer present
  bool has_summary_ = false;
  bool has_message_counts_ = false;  // a Statistics record with channel_message_counts
  std::map<uint16_t, McapChannel> channels_;
  std::map<uint16_t, std::string> schemas_;  // id -> name
  // Chunk offset -> channels with messages in it (from Chunk Index records that list them).
  std::unordered_map<uint64_t, std::vector<uint16_t>> chunk_channels_;
};

}  // namespace keel::io
