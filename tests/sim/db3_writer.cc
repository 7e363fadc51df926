#include "tests/sim/db3_writer.h"

#include <sqlite3.h>

#include <stdexcept>

namespace keel::sim {

Db3Writer::Db3Writer(const std::string& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    sqlite3_close(db_);
    throw std::runtime_error("cannot write " + path);
  }
  exec("PRAGMA journal_mode=MEMORY");
  exec("PRAGMA synchronous=OFF");
  exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL)");
  exec("INSERT INTO schema VALUES (4, 'keel-sim')");
  exec(
      "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
      "metadata TEXT NOT NULL)");
  exec(
      "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
      "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,"
      "type_description_hash TEXT NOT NULL)");
  exec(
      "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT NULL,"
      "encoding TEXT NOT NULL,encoded_message_definition TEXT NOT NULL,"
      "type_description_hash TEXT NOT NULL)");
  exec(
      "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
      "timestamp INTEGER NOT NULL, data BLOB NOT NULL)");
  exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC)");
  exec("BEGIN");
  if (sqlite3_prepare_v2(db_, "INSERT INTO messages (timestamp, topic_id, data) VALUES (?, ?, ?)",
                         -1, &insert_, nullptr) != SQLITE_OK)
    throw std::runtime_error(path_ + ": " + sqlite3_errmsg(db_));
}

Db3Writer::~Db3Writer() {
  try {
    close();
  } catch (...) {
  }
}

void Db3Writer::exec(const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : "unknown error";
    sqlite3_free(error);
    throw std::runtime_error(path_ + ": " + message + " (" + sql + ")");
  }
}

int64_t Db3Writer::add_topic(const std::string& name, const std::string& type,
                             const std::string& definition) {
  const int64_t id = next_topic_++;
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db_, "INSERT INTO topics VALUES (?, ?, ?, 'cdr', '', '')", -1, &s, nullptr);
  sqlite3_bind_int64(s, 1, id);
  sqlite3_bind_text(s, 2, name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s, 3, type.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(s);
  sqlite3_finalize(s);
  if (rc != SQLITE_DONE) throw std::runtime_error(path_ + ": " + sqlite3_errmsg(db_));
  sqlite3_prepare_v2(
      db_,
      "INSERT INTO message_definitions (topic_type, encoding, "
      "encoded_message_definition, type_description_hash) VALUES (?, 'ros2msg', ?, '')",
      -1, &s, nullptr);
  sqlite3_bind_text(s, 1, type.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s, 2, definition.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_step(s);
  sqlite3_finalize(s);
  return id;
}

void Db3Writer::write(int64_t topic_id, int64_t timestamp_ns, const std::vector<uint8_t>& data) {
  sqlite3_bind_int64(insert_, 1, timestamp_ns);
  sqlite3_bind_int64(insert_, 2, topic_id);
  sqlite3_bind_blob(insert_, 3, data.data(), static_cast<int>(data.size()), SQLITE_STATIC);
  const int rc = sqlite3_step(insert_);
  sqlite3_reset(insert_);
  if (rc != SQLITE_DONE) throw std::runtime_error(path_ + ": " + sqlite3_errmsg(db_));
  bytes_ += data.size();
}

void Db3Writer::close() {
  if (!db_) return;
  sqlite3_finalize(insert_);
  insert_ = nullptr;
  exec("COMMIT");
  const int rc = sqlite3_close(db_);
  db_ = nullptr;
  if (rc != SQLITE_OK) throw std::runtime_error("cannot close " + path_);
}

}  // namespace keel::sim
