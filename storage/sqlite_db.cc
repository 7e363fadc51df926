#include "storage/sqlite_db.h"

#include <sqlite3.h>

namespace keel::storage {

namespace {

std::string db_name(sqlite3* db) {
  const char* name = db ? sqlite3_db_filename(db, "main") : nullptr;
  return name && *name ? name : "sqlite";
}

std::string error_text(sqlite3* db, int code) {
  return db ? sqlite3_errmsg(db) : sqlite3_errstr(code);
}

}  // namespace

SqliteError::SqliteError(const std::string& message, int code)
    : std::runtime_error(message), code_(code) {}

// --- Statement ---

bool SqliteError::disk_full() const { return (code_ & 0xff) == SQLITE_FULL; }

Statement::Statement(sqlite3* db, const std::string& sql) : db_(db), sql_(sql) {
  const int code = sqlite3_prepare_v3(db_, sql.c_str(), static_cast<int>(sql.size() + 1),
                                      SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr);
  if (code != SQLITE_OK) fail(code, "prepare");
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::fail(int code, const std::string& what) const {
  throw SqliteError(
      db_name(db_) + ": " + what + " failed: " + error_text(db_, code) + " (SQL: " + sql_ + ")",
      sqlite3_extended_errcode(db_));
}

Statement& Statement::bind_int64(int index, int64_t value) {
  const int code = sqlite3_bind_int64(stmt_, index, value);
  if (code != SQLITE_OK) fail(code, "bind ?" + std::to_string(index));
  return *this;
}

Statement& Statement::bind_double(int index, double value) {
  const int code = sqlite3_bind_double(stmt_, index, value);
  if (code != SQLITE_OK) fail(code, "bind ?" + std::to_string(index));
  return *this;
}

Statement& Statement::bind_text(int index, const std::string& value) {
  const int code = sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()),
                                     SQLITE_TRANSIENT);
  if (code != SQLITE_OK) fail(code, "bind ?" + std::to_string(index));
  return *this;
}

Statement& Statement::bind_null(int index) {
  const int code = sqlite3_bind_null(stmt_, index);
  if (code != SQLITE_OK) fail(code, "bind ?" + std::to_string(index));
  return *this;
}

Statement& Statement::bind_text_or_null(int index, const std::string& value) {
  return value.empty() ? bind_null(index) : bind_text(index, value);
}

bool Statement::step() {
  const int code = sqlite3_step(stmt_);
  if (code == SQLITE_ROW) return true;
  if (code == SQLITE_DONE) return false;
  fail(code, "step");
}

void Statement::run() {
  while (step()) {
  }
}

int Statement::column_count() const { return sqlite3_column_count(stmt_); }

int Statement::column_type(int column) const { return sqlite3_column_type(stmt_, column); }

int64_t Statement::column_int64(int column) const { return sqlite3_column_int64(stmt_, column); }

double Statement::column_double(int column) const { return sqlite3_column_double(stmt_, column); }

std::string Statement::column_text(int column) const {
  const auto* text = sqlite3_column_text(stmt_, column);
  if (!text) return {};
  return std::string(reinterpret_cast<const char*>(text),
                     static_cast<size_t>(sqlite3_column_bytes(stmt_, column)));
}

bool Statement::column_is_null(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

// --- Database ---

Database::Database(const std::filesystem::path& file, const DatabaseOptions& options)
    : file_(file) {
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX;
  const int code = sqlite3_open_v2(file.c_str(), &db_, flags, nullptr);
  if (code != SQLITE_OK) {
    const std::string message = error_text(db_, code);
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw SqliteError(file.string() + ": cannot open database: " + message, code);
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, options.busy_timeout_ms);
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA foreign_keys=ON");
  exec("PRAGMA synchronous=FULL");
  if (options.query_only) exec("PRAGMA query_only=ON");
}

Database::~Database() {
  statements_.clear();  // finalize before closing
  sqlite3_close_v2(db_);
}

void Database::exec(const std::string& sql) {
  char* message = nullptr;
  const int code = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message);
  if (code != SQLITE_OK) {
    const std::string text = message ? message : sqlite3_errstr(code);
    sqlite3_free(message);
    throw SqliteError(file_.string() + ": " + text + " (SQL: " + sql + ")",
                      sqlite3_extended_errcode(db_));
  }
}

StatementRef Database::cached(const std::string& sql) {
  auto it = statements_.find(sql);
  if (it == statements_.end())
    it = statements_.emplace(sql, std::make_unique<Statement>(db_, sql)).first;
  return StatementRef(*it->second);
}

int64_t Database::changes() const { return sqlite3_changes64(db_); }

// --- Transaction ---

Transaction::Transaction(Database& db, Mode mode) : db_(db) {
  db_.exec(mode == Mode::kImmediate ? "BEGIN IMMEDIATE" : "BEGIN DEFERRED");
}

Transaction::~Transaction() {
  if (done_) return;
  try {
    db_.exec("ROLLBACK");
  } catch (...) {
    // SQLite may have rolled back already (e.g. after SQLITE_FULL); nothing more to undo.
  }
}

void Transaction::commit() {
  db_.exec("COMMIT");
  done_ = true;
}

}  // namespace keel::storage
