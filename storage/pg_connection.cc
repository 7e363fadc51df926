#include "storage/pg_connection.h"

#include "storage/open_store.h"

namespace keel::storage {

PgConnection::PgConnection(const std::string& url) : connection_(url) {}

const std::string& PgConnection::statement(const std::string& sql) {
  auto found = names_.find(sql);
  if (found != names_.end()) return found->second;
  const std::string name = "k" + std::to_string(names_.size());
  connection_.prepare(name, sql);
  return names_.emplace(sql, name).first->second;
}

PgPool::PgPool(std::string url, size_t max_connections)
    : url_(std::move(url)), max_connections_(std::max<size_t>(1, max_connections)) {
  // Fail at once on a wrong URL rather than on the first request.
  idle_.push_back(connect());
  open_ = 1;
}

std::unique_ptr<PgConnection> PgPool::connect() {
  try {
    return std::make_unique<PgConnection>(url_);
  } catch (const pqxx::broken_connection& error) {
    std::string why = error.what();
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw Unavailable("cannot connect to " + redact_database_url(url_) + ": " + why);
  }
}

std::unique_ptr<PgConnection> PgPool::acquire() {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return !idle_.empty() || open_ < max_connections_; });
    if (!idle_.empty()) {
      auto connection = std::move(idle_.back());
      idle_.pop_back();
      return connection;
    }
    ++open_;  // reserve the slot before connecting outside the lock
  }
  try {
    return connect();
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    --open_;
    freed_.notify_one();
    throw;
  }
}

void PgPool::release(std::unique_ptr<PgConnection> connection) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (connection && connection->raw().is_open()) {
    idle_.push_back(std::move(connection));
  } else {
    --open_;  // a broken connection is dropped; the next acquire opens a fresh one
  }
  freed_.notify_one();
}

std::string PgPool::lost_connection(const std::exception& error) const {
  std::string why = error.what();
  while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
  return "lost the connection to " + redact_database_url(url_) + ": " + why;
}

void PgPool::commit(pqxx::transaction_base& transaction, Lease& lease) {
  try {
    transaction.commit();
  } catch (const pqxx::broken_connection& error) {
    lease.discard();
    throw Unavailable(lost_connection(error) +
                      " (during a commit: it may or may not have "
                      "taken effect)");
  } catch (const pqxx::in_doubt_error& error) {
    lease.discard();
    throw Unavailable(lost_connection(error) +
                      " (during a commit: it may or may not have "
                      "taken effect)");
  }
}

}  // namespace keel::storage
