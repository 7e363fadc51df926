// Writes rosbag2's SQLite3 storage (.db3) with the tables rosbag2 (Jazzy, schema version 4)
// creates: schema, metadata, topics, message_definitions, messages (+ timestamp_idx).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace keel::sim {

class Db3Writer {
 public:
  explicit Db3Writer(const std::string& path);  // throws naming the path
  ~Db3Writer();
  Db3Writer(const Db3Writer&) = delete;
  Db3Writer& operator=(const Db3Writer&) = delete;

  // Returns the topic id; `definition` is the ros2msg text for message_definitions.
  int64_t add_topic(const std::string& name, const std::string& type,
                    const std::string& definition);
  void write(int64_t topic_id, int64_t timestamp_ns, const std::vector<uint8_t>& data);
  uint64_t bytes_written() const { return bytes_; }  // message bytes so far (for splitting)
  void close();

 private:
  void exec(const std::string& sql);
  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  int64_t next_topic_ = 1;
  uint64_t bytes_ = 0;
};

}  // namespace keel::sim
