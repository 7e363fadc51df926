#include "storage/pg_notifier.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <memory>
#include <pqxx/pqxx>

#include "storage/open_store.h"
#include "storage/pg_connection.h"
#include "storage/pg_listener.h"

namespace keel::storage {

namespace {

// The same change twice in one batch is said once (listeners re-read what they need).
void drop_repeats(std::vector<Change>& changes) {
  std::vector<Change> kept;
  for (Change& change : changes) {
    bool seen = false;
    for (const Change& k : kept)
      seen |= k.kind == change.kind && k.job_id == change.job_id && k.state == change.state &&
              k.project == change.project;
    if (!seen) kept.push_back(std::move(change));
  }
  changes.swap(kept);
}

}  // namespace

PgNotifier::PgNotifier(std::string database_url, std::string origin)
    : database_url_(std::move(database_url)), origin_(std::move(origin)) {
  thread_ = std::thread([this] { run(); });
}

PgNotifier::~PgNotifier() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  queued_.notify_all();
  thread_.join();
}

void PgNotifier::send(const std::vector<Change>& changes) {
  if (changes.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_.insert(pending_.end(), changes.begin(), changes.end());
  }
  queued_.notify_one();
}

void PgNotifier::run() {
  std::unique_ptr<pqxx::connection> connection;
  auto backoff = std::chrono::milliseconds(100);
  for (;;) {
    std::vector<Change> batch;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      queued_.wait(lock, [&] { return stop_ || !pending_.empty(); });
      if (pending_.empty()) return;  // stopping with nothing left to send
      batch.swap(pending_);
    }
    drop_repeats(batch);
    try {
      if (!connection) {
        connection = std::make_unique<pqxx::connection>(database_url_);
        pqxx::nontransaction setup(*connection);
        // This connection writes no data: its commits need not wait for the WAL flush.
        setup.exec("SET synchronous_commit = off");
      }
      pqxx::nontransaction work(*connection);  // autocommit: one statement, one round trip
      for (const std::string& payload : encode_changes(origin_, batch))
        work.exec_params("SELECT pg_notify($1, $2)", kChangeChannel, payload);
      backoff = std::chrono::milliseconds(100);
    } catch (const std::exception& error) {
      // The batch is lost to other replicas (their fallback tick covers it); reconnect.
      spdlog::warn("change feed: cannot notify other replicas: {}", error.what());
      connection.reset();
      std::unique_lock<std::mutex> lock(mutex_);
      if (queued_.wait_for(lock, backoff, [&] { return stop_; })) return;
      backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
    }
  }
}

}  // namespace keel::storage
