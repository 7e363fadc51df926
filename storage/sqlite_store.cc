// SQLite under the store's rules: the Sql interface (storage/sql.h) over the connections of
// storage/sqlite_db.h, and open_sqlite_store().
//
// Concurrency: SQLite admits one writer at a time, so all writes go through one connection
// behind a mutex (BEGIN IMMEDIATE ... COMMIT, synchronous=FULL). Reads use a small pool of
// read-only connections: in WAL mode they see the last committed state without waiting for
// the writer, so GET /v1/jobs/{id} on many threads never queues behind an fsync, and each
// connection caches its prepared statements. Upload chunks are written and fsynced outside
// the write lock (Sql::Mode::kFileWrite), so a large chunk does not stall other requests.
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <mutex>

#include "storage/migrations.h"
#include "storage/sql_store.h"
#include "storage/sqlite_db.h"

namespace keel::storage {

namespace fs = std::filesystem;

namespace {

const SqlFragments kFragments = {
    {"for_update", ""},  // the write transaction holds the whole database
    {"skip_locked", ""},
    {"instr", "instr"},
    {"rowid", "rowid"},
    {"stage_seconds",
     "(SELECT json_group_array(json_array(o.stage, o.seconds)) FROM stage_outputs o "
     "WHERE o.job_id = j.id)"},
};

class SqliteTx : public SqlTx {
 public:
  // With `lock`, each statement takes it and commits alone (Sql::Mode::kFileWrite).
  explicit SqliteTx(Database& db, std::mutex* lock = nullptr) : db_(db), lock_(lock) {}

  SqlRows query(const std::string& sql, const std::vector<SqlValue>& params) override {
    SqlRows rows;
    run(sql, params, [&](Statement& statement) {
      while (statement.step()) {
        std::vector<SqlRow::Cell> cells(statement.column_count());
        for (int i = 0; i < static_cast<int>(cells.size()); ++i) {
          const int type = statement.column_type(i);
          if (type == SQLITE_INTEGER) cells[i] = statement.column_int64(i);
          if (type == SQLITE_FLOAT) cells[i] = statement.column_double(i);
          if (type == SQLITE_TEXT || type == SQLITE_BLOB) cells[i] = statement.column_text(i);
        }
        rows.emplace_back(std::move(cells));
      }
    });
    return rows;
  }

  int64_t exec(const std::string& sql, const std::vector<SqlValue>& params) override {
    int64_t changed = 0;
    run(sql, params, [&](Statement& statement) {
      statement.run();
      changed = db_.changes();
    });
    return changed;
  }

 private:
  template <typename Use>
  void run(const std::string& sql, const std::vector<SqlValue>& params, Use use) {
    std::unique_lock<std::mutex> guard;
    if (lock_) guard = std::unique_lock<std::mutex>(*lock_);
    auto statement = db_.cached(translate_sql(sql, kFragments, /*dollar=*/false));
    for (size_t i = 0; i < params.size(); ++i) {
      const int index = static_cast<int>(i + 1);
      std::visit(
          [&](const auto& value) {
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, std::nullptr_t>)
              statement->bind_null(index);
            else if constexpr (std::is_same_v<T, int64_t>)
              statement->bind_int64(index, value);
            else if constexpr (std::is_same_v<T, double>)
              statement->bind_double(index, value);
            else
              statement->bind_text(index, value);
          },
          params[i]);
    }
    use(*statement);
  }

  Database& db_;
  std::mutex* lock_;
};

class SqliteSql : public Sql {
 public:
  explicit SqliteSql(const fs::path& data_dir)
      : file_(data_dir / "keel.db"), writer_(std::make_unique<Database>(file_)) {
    apply_migrations(*writer_, sqlite_migrations());
    // Recovery (temp files of cut writes, uncommitted upload bytes) is for the first process
    // on the folder only: a second one (`keel-server token ...` while the server runs) must
    // not cut files the live server is writing. An exclusive flock held for the store's
    // lifetime tells which one is first; the kernel drops it when the process dies.
    lock_fd_ = ::open((data_dir / "keel.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ >= 0 && ::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(lock_fd_);
      lock_fd_ = -1;
      first_on_folder_ = false;
    }
  }
  ~SqliteSql() override {
    if (lock_fd_ >= 0) ::close(lock_fd_);
  }
  bool first_on_folder() const { return first_on_folder_; }

 protected:
  void transact(Mode mode, const std::function<void(SqlTx&)>& work) override {
    if (mode == Mode::kRead) {
      Reader reader(*this);
      Transaction snapshot(*reader.db, Transaction::Mode::kDeferred);
      SqliteTx tx(*reader.db);
      work(tx);
      snapshot.commit();
      return;
    }
    std::vector<Change> changes;
    try {
      if (mode == Mode::kFileWrite) {
        SqliteTx tx(*writer_, &write_mutex_);
        work(tx);
        changes.swap(tx.changes);
      } else {
        std::lock_guard<std::mutex> lock(write_mutex_);
        Transaction transaction(*writer_);
        SqliteTx tx(*writer_);
        work(tx);
        transaction.commit();
        changes.swap(tx.changes);
      }
    } catch (const SqliteError& error) {
      // A full disk rolls the transaction back: tell the caller in its own terms.
      if (error.disk_full())
        throw StorageFull(std::string("no space left for the database: ") + error.what());
      throw;
    }
    changed(changes);  // outside the lock: listeners may call the store
  }

 private:
  // A read-only connection from the pool, returned to it (up to 8 kept) when done.
  struct Reader {
    explicit Reader(SqliteSql& sql) : owner(sql) {
      {
        std::lock_guard<std::mutex> lock(owner.readers_mutex_);
        if (!owner.readers_.empty()) {
          db = std::move(owner.readers_.back());
          owner.readers_.pop_back();
          return;
        }
      }
      db = std::make_unique<Database>(owner.file_, DatabaseOptions{5000, /*query_only=*/true});
    }
    ~Reader() {
      std::lock_guard<std::mutex> lock(owner.readers_mutex_);
      if (owner.readers_.size() < 8) owner.readers_.push_back(std::move(db));
    }
    SqliteSql& owner;
    std::unique_ptr<Database> db;
  };

  fs::path file_;
  std::unique_ptr<Database> writer_;
  std::mutex write_mutex_;
  std::mutex readers_mutex_;
  std::vector<std::unique_ptr<Database>> readers_;
  int lock_fd_ = -1;
  bool first_on_folder_ = true;
};

}  // namespace

std::unique_ptr<Store> open_sqlite_store(const fs::path& data_dir, Clock clock) {
  fs::create_directories(data_dir);
  auto sql = std::make_unique<SqliteSql>(data_dir);
  const StoreFiles files{data_dir, sql->first_on_folder(), 0};
  return std::make_unique<SqlStore>(std::move(sql), files, std::move(clock));
}

}  // namespace keel::storage
