// PostgreSQL under the store's rules: the Sql interface (storage/sql.h) over PgPool, with the
// change feed between replicas (PgChangeFeed).
#include "storage/pg_store.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <exception>

#include "storage/ids.h"
#include "storage/open_store.h"
#include "storage/pg_change_feed.h"
#include "storage/pg_connection.h"
#include "storage/pg_migrations.h"

namespace keel::storage {

namespace {

const SqlFragments kFragments = {
    // NO KEY: rows that reference the job (logs, artifacts) may still be inserted meanwhile.
    {"for_update", " FOR NO KEY UPDATE"},
    {"skip_locked", " FOR UPDATE SKIP LOCKED"},
    {"instr", "strpos"},
    {"rowid", "seq"},
    {"stage_seconds",
     "(SELECT COALESCE(json_agg(json_build_array(o.stage, o.seconds) ORDER BY o.seq), '[]') "
     "FROM stage_outputs o WHERE o.job_id = j.id)::text"},
};

class PgSqlTx : public SqlTx {
 public:
  explicit PgSqlTx(PgTx& tx) : tx_(tx) {}

  SqlRows query(const std::string& sql, const std::vector<SqlValue>& params) override {
    const pqxx::result result = run(sql, params);
    SqlRows rows;
    rows.reserve(result.size());
    for (const pqxx::row& row : result) {
      std::vector<SqlRow::Cell> cells(row.size());
      for (pqxx::row::size_type i = 0; i < row.size(); ++i)
        if (!row[i].is_null()) cells[i] = std::string(row[i].c_str(), row[i].size());
      rows.emplace_back(std::move(cells));
    }
    return rows;
  }

  int64_t exec(const std::string& sql, const std::vector<SqlValue>& params) override {
    return run(sql, params).affected_rows();
  }

 private:
  pqxx::result run(const std::string& sql, const std::vector<SqlValue>& params) {
    std::vector<std::string> texts(params.size());
    std::vector<const char*> values(params.size(), nullptr);  // nullptr: NULL
    for (size_t i = 0; i < params.size(); ++i) {
      if (std::holds_alternative<std::nullptr_t>(params[i])) continue;
      if (const auto* number = std::get_if<int64_t>(&params[i])) texts[i] = std::to_string(*number);
      if (const auto* number = std::get_if<double>(&params[i])) texts[i] = pqxx::to_string(*number);
      if (const auto* text = std::get_if<std::string>(&params[i])) {
        // PostgreSQL text cannot hold NUL bytes; a text keeps everything else.
        texts[i] = *text;
        std::replace(texts[i].begin(), texts[i].end(), '\0', ' ');
      }
      values[i] = texts[i].c_str();
    }
    return tx_.exec_params(translate_sql(sql, kFragments, /*dollar=*/true), values);
  }

  PgTx& tx_;
};

class PgSql : public Sql {
 public:
  // Connects (Unavailable on failure), migrates and starts the change feed.
  explicit PgSql(const PgStoreOptions& options)
      : url_(with_connect_timeout(options.database_url, options.connect_timeout_s)),
        pool_(url_, options.max_connections) {
    apply_pg_migrations(pool_, pg_migrations());
    if (options.listen) listen(options.connect_timeout_s);
  }
  ~PgSql() override { feed_.reset(); }  // before the pool: its threads may use the store

 protected:
  void transact(Mode mode, const std::function<void(SqlTx&)>& work) override {
    std::vector<Change> changes;
    auto body = [&](PgTx& pg) {
      PgSqlTx tx(pg);
      work(tx);
      changes = std::move(tx.changes);
    };
    try {
      if (mode == Mode::kRead)
        pool_.snapshot(body);
      else
        pool_.transact(body);  // kFileWrite too: its row locks keep other replicas off
    } catch (const pqxx::disk_full& error) {
      throw StorageFull(std::string("no space left for the database: ") + error.what());
    }
    changed(changes);
    if (feed_) feed_->send(changes);
  }

 private:
  // This replica's changes go to the others after the commit; theirs arrive here.
  void listen(int connect_timeout_s) {
    PgChangeFeedOptions listen;
    listen.database_url = url_;
    listen.origin = random_hex(8);
    listen.deliver = [this](const std::vector<Change>& changes) { changed(changes); };
    // Notifications sent while the link was down are lost: every project's listeners are
    // told to re-read (a job_id "" change, as for a batch).
    listen.on_reconnect = [this] {
      try {
        std::vector<Change> reload;
        pool_.snapshot([&](PgTx& tx) {
          for (const pqxx::row& row : tx.work().exec("SELECT name FROM projects ORDER BY name")) {
            Change change;
            change.project = row[0].as<std::string>();
            reload.push_back(change);
          }
        });
        changed(reload);
      } catch (const std::exception& error) {
        spdlog::warn("change feed: after reconnecting: {}", error.what());
      }
    };
    feed_ = std::make_unique<PgChangeFeed>(std::move(listen));
    // The pool just connected, so the listener's connection normally follows within
    // milliseconds; if it does not, the store still works (the long poll's fallback tick).
    const auto wait = std::chrono::milliseconds(1000 * std::max(1, connect_timeout_s));
    if (!feed_->wait_listening(wait))
      spdlog::warn(
          "change feed: not listening yet after {} ms; changes of other replicas reach this "
          "one by the fallback poll until it is",
          wait.count());
  }

  std::string url_;
  PgPool pool_;
  std::unique_ptr<PgChangeFeed> feed_;
};

}  // namespace

PgStore::PgStore(const PgStoreOptions& options, Clock clock)
    : SqlStore(std::make_unique<PgSql>(options),
               StoreFiles{options.blob_dir, true, options.stale_file_age_s}, std::move(clock)) {}

}  // namespace keel::storage
