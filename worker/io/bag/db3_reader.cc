#include "worker/io/bag/db3_reader.h"

#include <sqlite3.h>

#include <map>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {

namespace {

[[noreturn]] void fail(sqlite3* db, const std::string& doing) {
  const int code = sqlite3_extended_errcode(db);
  std::string message = "SQLite: " + doing + ": " + sqlite3_errmsg(db);
  if ((code & 0xFF) == SQLITE_NOTADB) message += " (not a SQLite3 .db3 file?)";
  if ((code & 0xFF) == SQLITE_CORRUPT) message += " (truncated or corrupt .db3 file)";
  throw BagFormatError(message);
}

sqlite3_stmt* prepare(sqlite3* db, const char* sql, const std::string& doing) {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &statement, nullptr) != SQLITE_OK) fail(db, doing);
  return statement;
}

std::string text(sqlite3_stmt* statement, int column) {
  const unsigned char* t = sqlite3_column_text(statement, column);
  return t ? reinterpret_cast<const char*>(t) : "";
}

}  // namespace

Db3Reader::Db3Reader(const std::filesystem::path& path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX, nullptr) !=
      SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw BagFormatError("SQLite: cannot open: " + message);
  }
  try {
    read_topics();
  } catch (...) {
    sqlite3_close(db_);
    throw;
  }
}

Db3Reader::Db3Reader(const uint8_t* data, size_t size) {
  if (sqlite3_open_v2(":memory:", &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX, nullptr) !=
      SQLITE_OK) {
    sqlite3_close(db_);
    throw BagFormatError("SQLite: cannot open an in-memory database");
  }
  // READONLY: SQLite never writes to (or frees) the caller's bytes.
  if (sqlite3_deserialize(db_, "main", const_cast<unsigned char*>(data),
                          static_cast<sqlite3_int64>(size), static_cast<sqlite3_int64>(size),
                          SQLITE_DESERIALIZE_READONLY) != SQLITE_OK) {
    sqlite3_close(db_);
    throw BagFormatError("SQLite: cannot load the database image");
  }
  try {
    read_topics();
  } catch (...) {
    sqlite3_close(db_);
    throw;
  }
}

Db3Reader::~Db3Reader() { sqlite3_close(db_); }

void Db3Reader::read_topics() {
  std::map<int64_t, uint64_t> counts;
  {
    sqlite3_stmt* s = prepare(db_, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id",
                              "reading table messages");
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW)
      counts[sqlite3_column_int64(s, 0)] = static_cast<uint64_t>(sqlite3_column_int64(s, 1));
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) fail(db_, "counting messages");
  }
  sqlite3_stmt* s =
      prepare(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id",
              "reading table topics");
  int rc;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    Db3Topic t;
    t.id = sqlite3_column_int64(s, 0);
    t.name = text(s, 1);
    t.type = text(s, 2);
    t.serialization_format = text(s, 3);
    const auto it = counts.find(t.id);
    t.messages = it == counts.end() ? 0 : it->second;
    topics_.push_back(std::move(t));
  }
  sqlite3_finalize(s);
  if (rc != SQLITE_DONE) fail(db_, "reading table topics");
}

Db3Reader::Cursor Db3Reader::messages(int64_t topic_id) const {
  sqlite3_stmt* s =
      prepare(db_, "SELECT timestamp, data FROM messages WHERE topic_id = ? ORDER BY id",
              "reading table messages");
  sqlite3_bind_int64(s, 1, topic_id);
  return Cursor(db_, s);
}

Db3Reader::Cursor::Cursor(Cursor&& other) noexcept : db_(other.db_), statement_(other.statement_) {
  other.statement_ = nullptr;
}

Db3Reader::Cursor::~Cursor() { sqlite3_finalize(statement_); }

bool Db3Reader::Cursor::next(Db3Message& message) {
  if (!statement_) return false;
  const int rc = sqlite3_step(statement_);
  if (rc == SQLITE_DONE) return false;
  if (rc != SQLITE_ROW) fail(db_, "reading table messages");
  message.timestamp_ns = sqlite3_column_int64(statement_, 0);
  message.data = static_cast<const uint8_t*>(sqlite3_column_blob(statement_, 1));
  message.size = static_cast<size_t>(sqlite3_column_bytes(statement_, 1));
  if (!message.data) message.size = 0;
  return true;
}

}  // namespace keel::io
