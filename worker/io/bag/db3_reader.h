// rosbag2's SQLite3 storage (.db3, the ROS 2 default before Iron): tables `topics` (id, name,
// type, serialization_format, ...) and `messages` (id, topic_id, timestamp, data), read
// through SQLite (a Debian package) read-only. A cursor steps one row at a time, so memory
// stays bounded. Errors are BagFormatError; the bag reader adds file, topic and message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace keel::io {

struct Db3Topic {
  int64_t id = 0;
  std::string name;
  std::string type;                  // e.g. sensor_msgs/msg/Imu
  std::string serialization_format;  // "cdr"
  uint64_t messages = 0;
};

struct Db3Message {
  int64_t timestamp_ns = 0;       // the recorder's receive time
  const uint8_t* data = nullptr;  // valid until the cursor moves on
  size_t size = 0;
};

class Db3Reader {
 public:
  explicit Db3Reader(const std::filesystem::path& path);
  // A database image in memory (the fuzzer); `data` must outlive the reader.
  Db3Reader(const uint8_t* data, size_t size);
  ~Db3Reader();
  Db3Reader(const Db3Reader&) = delete;
  Db3Reader& operator=(const Db3Reader&) = delete;

  const std::vector<Db3Topic>& topics() const { return topics_; }

  // The messages of one topic in the order they were recorded (row id).
  class Cursor {
   public:
    ~Cursor();
    Cursor(Cursor&& other) noexcept;
    Cursor& operator=(Cursor&&) = delete;
    bool next(Db3Message& message);

   private:
    friend class Db3Reader;
    Cursor(sqlite3* db, sqlite3_stmt* statement) : db_(db), statement_(statement) {}
    sqlite3* db_;
    sqlite3_stmt* statement_;
  };
  Cursor messages(int64_t topic_id) const;

 private:
  void read_topics();

  sqlite3* db_ = nullptr;
  std::vector<Db3Topic> topics_;
};

}  // namespace keel::io
