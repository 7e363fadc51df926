#include "storage/connection_pool.h"

namespace keel::storage {

ConnectionPool::ConnectionPool(std::filesystem::path file, DatabaseOptions options, size_t max_idle)
    : file_(std::move(file)), options_(options), max_idle_(max_idle) {}

ConnectionPool::Handle ConnectionPool::acquire() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!idle_.empty()) {
      std::unique_ptr<Database> db = std::move(idle_.back());
      idle_.pop_back();
      return Handle(*this, std::move(db));
    }
  }
  return Handle(*this, std::make_unique<Database>(file_, options_));
}

void ConnectionPool::release(std::unique_ptr<Database> db) {
  if (!db) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (idle_.size() < max_idle_) idle_.push_back(std::move(db));
}

}  // namespace keel::storage
