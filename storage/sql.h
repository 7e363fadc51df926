// The small SQL interface the store's rules are written against (storage/sql_store.h), in the
// spirit of COLMAP's database.h: SQLite (sqlite_store.cc) and PostgreSQL (pg_store.cc)
// implement it; nothing above it knows which one runs.
//
// One statement text serves both databases:
//   - parameters are ?1, ?2, ... (PostgreSQL's layer writes them as $1, $2, ...);
//   - where the dialects truly differ, the text names a fragment in braces that each
//     dialect fills in (SqlFragments): {for_update} locks the rows a SELECT reads until the
//     commit (PostgreSQL; SQLite's write transaction holds the whole database already),
//     {skip_locked} also skips rows another transaction holds, {instr} is the position of a
//     text in another (1-based, 0 when absent), {rowid} orders rows by insertion where a
//     table has no seq column, {stage_seconds} is a job's finished stages and their seconds
//     as a JSON array text (the job aliased j).
// Each connection prepares a statement once and keeps it.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "storage/store.h"

namespace keel::storage {

// A statement's parameter: NULL, an integer, a real or a text.
using SqlValue = std::variant<std::nullptr_t, int64_t, double, std::string>;

// A result row. Columns are 0-based and read as the type asked for, as SQLite does
// (PostgreSQL's values arrive as text): NULL reads as "" or 0.
class SqlRow {
 public:
  using Cell = std::variant<std::monostate, int64_t, double, std::string>;
  explicit SqlRow(std::vector<Cell> cells) : cells_(std::move(cells)) {}
  bool is_null(int column) const;
  std::string text(int column) const;
  int64_t int64(int column) const;
  double real(int column) const;

 private:
  std::vector<Cell> cells_;
};
using SqlRows = std::vector<SqlRow>;

// The statements of one transaction.
class SqlTx {
 public:
  virtual ~SqlTx() = default;
  // Runs one statement and returns its rows (a SELECT, or a change with RETURNING).
  virtual SqlRows query(const std::string& sql, const std::vector<SqlValue>& params = {}) = 0;
  // Runs one statement that returns no rows and returns how many rows it changed.
  virtual int64_t exec(const std::string& sql, const std::vector<SqlValue>& params = {}) = 0;
  // The first row, or none.
  std::optional<SqlRow> row(const std::string& sql, const std::vector<SqlValue>& params = {});

  // The changes this transaction made, published to the store's change feed after the
  // commit (never for a rollback).
  std::vector<Change> changes;
};

class Sql {
 public:
  enum class Mode {
    kRead,   // a read-only snapshot: every statement sees one committed state
    kWrite,  // one atomic write transaction
    // A write whose work reads or writes files between its statements (an upload's chunk
    // or hash). PostgreSQL runs it as one transaction, whose row locks ({for_update}) keep
    // other replicas off the row meanwhile; SQLite, whose single write lock would stall
    // every other request for as long, commits each statement alone (one process owns a
    // SQLite folder: the caller's own lock is what orders the work).
    kFileWrite,
  };

  virtual ~Sql() = default;

  // Runs `work(SqlTx&)` in one transaction of `mode`, commits and returns what it returned.
  // Any exception rolls back. PostgreSQL runs `work` again from the start when the database
  // aborted it (deadlock, serialization failure, a connection lost before the commit), so
  // `work` must not keep state from a failed attempt. Throws StorageFull when the database
  // has no space left, Unavailable when it cannot be reached.
  template <typename Work>
  auto run(Mode mode, Work&& work) {
    using Result = decltype(work(std::declval<SqlTx&>()));
    if constexpr (std::is_void_v<Result>) {
      transact(mode, [&](SqlTx& tx) { work(tx); });
    } else {
      std::optional<Result> result;
      transact(mode, [&](SqlTx& tx) { result.emplace(work(tx)); });
      return std::move(*result);
    }
  }

  // Called with the changes of each commit (not while a lock is held) and, where the
  // database tells of other processes' commits (PostgreSQL's LISTEN), with theirs.
  void on_change(std::function<void(const std::vector<Change>&)> listener) {
    std::lock_guard<std::mutex> lock(mutex_);
    on_change_ = std::move(listener);
  }

 protected:
  virtual void transact(Mode mode, const std::function<void(SqlTx&)>& work) = 0;
  void changed(const std::vector<Change>& changes) {
    std::function<void(const std::vector<Change>&)> listener;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      listener = on_change_;
    }
    if (!changes.empty() && listener) listener(changes);
  }

 private:
  std::mutex mutex_;
  std::function<void(const std::vector<Change>&)> on_change_;
};

// A dialect's fills of the {name} fragments (see the top of this file).
using SqlFragments = std::map<std::string, std::string>;

// `sql` with its fragments filled in and, when `dollar` is set, ?N written as $N. Text in
// single quotes is kept as it is. Throws std::logic_error for an unknown fragment.
std::string translate_sql(const std::string& sql, const SqlFragments& fragments, bool dollar);

}  // namespace keel::storage
