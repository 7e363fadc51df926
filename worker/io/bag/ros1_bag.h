// A ROS1 bag read by Keel itself: ROS bag format 2.0 (wiki.ros.org/Bags/Format/2.0). The file
// is the line "#ROSBAG V2.0\n" then records, each a little-endian uint32 header length, the
// header (fields, each a uint32 length then "name=value"; `op` names the record), a uint32
// data length and the data. Records: the bag header (op 3: index_pos, where the index section
// starts), chunks (op 5: compression none, bz2 or lz4, and `size`, their records' bytes once
// uncompressed) holding connection (op 7) and message data (op 2: conn, time) records, each
// chunk followed by index data records (op 4, version 1: conn, count, then per message uint32
// sec, uint32 nsec, uint32 offset into the chunk's uncompressed records), and the index
// section: a connection record per connection (header conn, topic; data the publisher's
// connection header: type, md5sum, message_definition, ...) and a chunk info per chunk (op 6).
// lz4 chunks are roslz4's streams, which are LZ4 frames (lz4_Frame_format.md).
//
// Opening walks every record and checks it: every record and header field lies inside its
// container; every chunk is at most 1 GiB uncompressed and exactly as long as its `size` says
// (bz2 and lz4 decompress into a buffer that grows with what they produce, so a chunk that
// claims a huge size is refused before anything that size is allocated); every index entry
// points at a record of the chunk before it; chunk infos' chunk_pos at a chunk and the bag
// header's index_pos at a record. Errors are BagFormatError naming the bag and the record's
// byte offset.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/time.h"
#include "worker/io/bag/byte_source.h"

namespace keel::io {

struct Ros1Connection {
  uint32_t id = 0;
  std::string topic;
  std::string datatype;  // connection header `type`: sensor_msgs/Imu
  std::string md5sum;
  std::string message_definition;
};

// One message as recorded: its connection, the record time (the recorder's receive time) and
// its serialised bytes, valid until the cursor moves on.
struct Ros1Message {
  const Ros1Connection* connection = nullptr;
  TimeNs time_ns = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
};

enum class Ros1Compression { kNone, kBz2, kLz4 };

// Where a chunk's data lies in the file, and how long it is once uncompressed.
struct Ros1Chunk {
  uint64_t data_at = 0;
  uint32_t stored_size = 0, size = 0;
  Ros1Compression compression = Ros1Compression::kNone;
};

// One message of the index: its record time and where its record starts.
struct Ros1IndexEntry {
  TimeNs time_ns = 0;
  uint32_t chunk = 0;   // into the bag's chunks, in file order
  uint32_t offset = 0;  // into the chunk's uncompressed records
  uint32_t conn = 0;    // its connection
};

class Ros1Bag {
 public:
  // `name` is the bag as errors show it (display_path).
  Ros1Bag(std::shared_ptr<const ByteSource> bytes, std::string name);
  ~Ros1Bag();
  Ros1Bag(const Ros1Bag&) = delete;
  Ros1Bag& operator=(const Ros1Bag&) = delete;

  const std::string& name() const { return name_; }
  // By connection id.
  const std::map<uint32_t, Ros1Connection>& connections() const { return connections_; }
  // Messages of a topic (all its connections); 0 for a topic the bag does not hold.
  size_t message_count(const std::string& topic) const;

  // The messages of a topic in time order (equal times in recording order), as rosbag's View
  // gives them. The bag must outlive the cursor. Errors are BagFormatError naming the chunk.
  class Cursor {
   public:
    bool next(Ros1Message& message);

   private:
    friend class Ros1Bag;
    Cursor(const Ros1Bag& bag, const std::string& topic);
    const Ros1Bag* bag_;
    const std::vector<Ros1IndexEntry>* entries_ = nullptr;  // the topic's, or null
    size_t next_ = 0;
    uint32_t loaded_chunk_ = UINT32_MAX;
    std::vector<uint8_t> chunk_;  // records of the loaded chunk, uncompressed
  };
  Cursor messages(const std::string& topic) const { return Cursor(*this, topic); }

 private:
  // A chunk's records, uncompressed and exactly as long as its `size` says.
  void read_chunk(const Ros1Chunk& chunk, const std::string& where,
                  std::vector<uint8_t>& out) const;

  std::shared_ptr<const ByteSource> bytes_;
  std::string name_;
  std::map<uint32_t, Ros1Connection> connections_;
  std::vector<Ros1Chunk> chunks_;
  std::map<std::string, std::vector<Ros1IndexEntry>> entries_;  // by topic, in time order
};

}  // namespace keel::io
