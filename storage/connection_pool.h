// Read-only SQLite connections shared by the server's threads. In WAL mode readers never
// wait for the writer (not even for its fsync) and each connection keeps its own prepared
// statements, so GET requests on several threads run in parallel.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <vector>

#include "storage/sqlite_db.h"

namespace keel::storage {

class ConnectionPool {
 public:
  // Opens connections lazily; keeps up to `max_idle` of them between uses.
  ConnectionPool(std::filesystem::path file, DatabaseOptions options, size_t max_idle = 8);

  // A connection checked out for one thread; returned to the pool when destroyed.
  class Handle {
   public:
    Handle(ConnectionPool& pool, std::unique_ptr<Database> db) : pool_(&pool), db_(std::move(db)) {}
    ~Handle() { pool_->release(std::move(db_)); }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    Database& operator*() const { return *db_; }
    Database* operator->() const { return db_.get(); }

   private:
    ConnectionPool* pool_;
    std::unique_ptr<Database> db_;
  };

  Handle acquire();

 private:
  void release(std::unique_ptr<Database> db);

  std::filesystem::path file_;
  DatabaseOptions options_;
  size_t max_idle_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Database>> idle_;
};

}  // namespace keel::storage
