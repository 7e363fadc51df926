// PostgreSQL connections for PgStore (libpqxx): a connection that prepares each SQL text
// once (like Database::cached for SQLite), a pool shared by the server's threads, and
// `PgPool::transact`, which runs one unit of work in one transaction and retries it when
// PostgreSQL aborts it for a deadlock or a serialization failure, or when the connection
// broke before anything was committed.
#pragma once

#include <pqxx/pqxx>

#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "storage/store.h"

namespace keel::storage {

// One open connection and the statements prepared on it.
class PgConnection {
 public:
  explicit PgConnection(const std::string& url);

  pqxx::connection& raw() { return connection_; }
  // The name of `sql` prepared on this connection (prepared on first use).
  const std::string& statement(const std::string& sql);

 private:
  pqxx::connection connection_;
  std::unordered_map<std::string, std::string> names_;  // SQL text -> statement name
};

// A transaction on a pooled connection: statements are prepared once per connection.
class PgTx {
 public:
  PgTx(PgConnection& connection, pqxx::transaction_base& work)
      : connection_(connection), work_(work) {}

  // `sql` with $1, $2, ... bound to `values` (nullptr: NULL).
  pqxx::result exec_params(const std::string& sql, const std::vector<const char*>& values) {
    return work_.exec_prepared(connection_.statement(sql),
                               pqxx::prepare::make_dynamic_params(values));
  }
  pqxx::transaction_base& work() { return work_; }

 private:
  PgConnection& connection_;
  pqxx::transaction_base& work_;
};

class PgPool {
 public:
  // Connects once at construction (Unavailable on failure); more connections are
  // opened on demand up to `max_connections`, then callers wait for a free one.
  PgPool(std::string url, size_t max_connections);

  // Runs `work(tx)` in one READ COMMITTED transaction and commits. Retries (a few times)
  // when PostgreSQL aborted it (deadlock, serialization failure) or the connection broke
  // before the commit; an error during the commit itself is not retried (it may have
  // committed). A connection that stays broken is Unavailable. Other exceptions propagate
  // after the rollback.
  template <typename Work>
  auto transact(Work&& work) {
    return run<pqxx::work>(std::forward<Work>(work));
  }
  // The same in a read-only REPEATABLE READ transaction: every statement of `work` sees one
  // snapshot, as in SQLite's read transactions.
  template <typename Work>
  auto snapshot(Work&& work) {
    return run<pqxx::transaction<pqxx::repeatable_read, pqxx::read_only>>(std::forward<Work>(work));
  }

  const std::string& url() const { return url_; }

 private:
  static constexpr int kAttempts = 4;
  template <typename Transaction, typename Work>
  auto run(Work&& work) {
    for (int attempt = 1;; ++attempt) {
      Lease lease(*this);
      try {
        Transaction transaction(lease->raw());
        PgTx tx(*lease, transaction);
        if constexpr (std::is_void_v<decltype(work(tx))>) {
          work(tx);
          commit(transaction, lease);
          return;
        } else {
          auto result = work(tx);
          commit(transaction, lease);
          return result;
        }
      } catch (const pqxx::transaction_rollback&) {
        if (attempt >= kAttempts) throw;
      } catch (const pqxx::broken_connection& error) {
        lease.discard();
        if (attempt >= kAttempts) throw Unavailable(lost_connection(error));
      }
    }
  }
  class Lease {
   public:
    explicit Lease(PgPool& pool) : pool_(pool), connection_(pool.acquire()) {}
    ~Lease() { pool_.release(std::move(connection_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    PgConnection* operator->() { return connection_.get(); }
    PgConnection& operator*() { return *connection_; }
    void discard() { connection_.reset(); }

   private:
    PgPool& pool_;
    std::unique_ptr<PgConnection> connection_;
  };

  // A commit whose outcome is unknown (the link broke during it) must not be retried:
  // Unavailable saying so.
  void commit(pqxx::transaction_base& transaction, Lease& lease);
  std::string lost_connection(const std::exception& error) const;
  std::unique_ptr<PgConnection> acquire();
  void release(std::unique_ptr<PgConnection> connection);
  std::unique_ptr<PgConnection> connect();

  std::string url_;
  size_t max_connections_;
  std::mutex mutex_;
  std::condition_variable freed_;
  std::vector<std::unique_ptr<PgConnection>> idle_;
  size_t open_ = 0;
};

}  // namespace keel::storage
