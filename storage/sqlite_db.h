// Small RAII wrappers over the SQLite C API: a connection (Database), a prepared statement
// with typed bind/column (Statement), a scope that resets a cached statement (StatementRef)
// and a transaction that rolls back unless committed (Transaction).
//
// Only storage/sqlite_*.cc include this header: nothing SQLite-specific leaks through
// storage/store.h. A Database is used by one thread at a time (SQLITE_OPEN_NOMUTEX); the
// store serializes access (one writer behind a mutex, readers from a pool).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>

struct sqlite3;
struct sqlite3_stmt;

namespace keel::storage {

// A failed SQLite call. what() names the database file, the SQL and SQLite's message.
class SqliteError : public std::runtime_error {
 public:
  SqliteError(const std::string& message, int code);
  int code() const { return code_; }  // the SQLite (extended) result code
  bool disk_full() const;              // SQLITE_FULL: the database file could not grow

 private:
  int code_;
};

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters are 1-based as in SQLite; columns are 0-based.
  Statement& bind_int64(int index, int64_t value);
  Statement& bind_double(int index, double value);
  Statement& bind_text(int index, const std::string& value);
  Statement& bind_null(int index);
  // Binds NULL for "" (optional references such as a mission's CAD blob).
  Statement& bind_text_or_null(int index, const std::string& value);

  // Advances one row: true while there is a row to read, false when done.
  bool step();
  // Runs a statement that returns no rows (INSERT/UPDATE/DELETE).
  void run();

  int column_count() const;
  // SQLITE_INTEGER, SQLITE_FLOAT, SQLITE_TEXT, SQLITE_BLOB or SQLITE_NULL (sqlite3.h).
  int column_type(int column) const;
  int64_t column_int64(int column) const;
  double column_double(int column) const;
  std::string column_text(int column) const;  // "" for NULL
  bool column_is_null(int column) const;

  // Makes the statement ready to run again and drops its bindings.
  void reset();
  const std::string& sql() const { return sql_; }

 private:
  [[noreturn]] void fail(int code, const std::string& what) const;

  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

// A cached statement checked out for one use; reset on scope exit so no read snapshot stays
// open on the connection (a stepped-but-not-reset SELECT would pin an old WAL snapshot).
class StatementRef {
 public:
  explicit StatementRef(Statement& statement) : statement_(&statement) {}
  ~StatementRef() { statement_->reset(); }
  StatementRef(const StatementRef&) = delete;
  StatementRef& operator=(const StatementRef&) = delete;
  Statement* operator->() const { return statement_; }
  Statement& operator*() const { return *statement_; }

 private:
  Statement* statement_;
};

struct DatabaseOptions {
  int busy_timeout_ms = 5000;  // waits for another connection's write lock before SQLITE_BUSY
  bool query_only = false;     // reader connections refuse writes
};

class Database {
 public:
  // Opens (creating if needed) the file, turns on WAL, foreign keys, busy_timeout and
  // synchronous=FULL (a commit is on disk when it returns: the job queue is durable).
  Database(const std::filesystem::path& file, const DatabaseOptions& options = {});
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  // Runs one or more statements without results (schema, pragmas, BEGIN/COMMIT).
  void exec(const std::string& sql);
  // A prepared statement kept for the connection's lifetime: parse once, run many times.
  StatementRef cached(const std::string& sql);

  int64_t changes() const;  // rows changed by the last INSERT/UPDATE/DELETE
  const std::filesystem::path& file() const { return file_; }
  sqlite3* handle() const { return db_; }

 private:
  sqlite3* db_ = nullptr;
  std::filesystem::path file_;
  std::unordered_map<std::string, std::unique_ptr<Statement>> statements_;
};

// BEGIN IMMEDIATE (takes the write lock at once, so two writers never deadlock upgrading a
// read lock) or BEGIN DEFERRED (a consistent read snapshot). Rolls back in the destructor
// unless commit() was called.
class Transaction {
 public:
  enum class Mode { kImmediate, kDeferred };
  explicit Transaction(Database& db, Mode mode = Mode::kImmediate);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  Database& db_;
  bool done_ = false;
};

}  // namespace keel::storage
