// Shared helpers for the storage tests: a fresh data directory per test, a clock the test
// moves by hand, and the typed fixture that runs each store test on SQLite and PostgreSQL.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>

#include <pqxx/pqxx>

#include "storage/pg_store.h"
#include "storage/sqlite_db.h"
#include "storage/store.h"
#include "tests/storage/pg_test_server.h"
#include "tests/temp_dir.h"

namespace keel::storage::testing {

using keel::testing::PgTestServer;

using keel::testing::read_file;
using keel::testing::TempDir;
using keel::testing::write_file;

// Time that only moves when the test says so.
class FakeClock {
 public:
  explicit FakeClock(int64_t start_ms = 1'700'000'000'000)
      : now_ms_(std::make_shared<std::atomic<int64_t>>(start_ms)) {}
  Clock clock() const {
    auto now = now_ms_;
    return [now] { return now->load(); };
  }
  void advance_ms(int64_t ms) { *now_ms_ += ms; }
  int64_t now_ms() const { return now_ms_->load(); }

 private:
  std::shared_ptr<std::atomic<int64_t>> now_ms_;
};

// Deterministic pseudo-random bytes (different seeds give different content).
inline std::string random_bytes(size_t size, unsigned seed) {
  std::mt19937 generator(seed);
  std::string bytes(size, '\0');
  for (char& c : bytes) c = static_cast<char>(generator() & 0xff);
  return bytes;
}

// The stores the typed suite runs against.
enum class Backend { kSqlite, kPostgres };

inline std::string backend_name(const ::testing::TestParamInfo<Backend>& info) {
  return info.param == Backend::kSqlite ? "SQLite" : "PostgreSQL";
}

// A store with a fake clock: SQLite in a fresh folder, or PostgreSQL (the binary's private
// server, a fresh database per test) with its blob folder in a fresh folder. PostgreSQL
// tests skip, saying why, where PostgreSQL is not installed.
class StoreTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    if (GetParam() == Backend::kPostgres) {
      PgTestServer* server = PgTestServer::shared();
      if (!server) GTEST_SKIP() << PgTestServer::reason();
      database_url_ = server->create_database();
    }
    reopen();
  }
  bool postgres() const { return GetParam() == Backend::kPostgres; }
  // Closes the store and opens it again on the same data (a server restart).
  void reopen() {
    store_.reset();
    store_ = open_another();
  }
  // Another store on the same data: for PostgreSQL a second replica (same database and blob
  // folder); for SQLite a second process's view of the same folder.
  std::unique_ptr<Store> open_another() {
    if (!postgres()) return open_sqlite_store(dir_.path(), clock_.clock());
    PgStoreOptions options;
    options.database_url = database_url_;
    options.blob_dir = dir_.path();
    return std::make_unique<PgStore>(options, clock_.clock());
  }
  // Runs SQL on the store's database (both dialects accept what the tests send).
  int64_t count_rows(const std::string& table) {
    if (!postgres()) {
      Database db(dir_.path() / "keel.db");
      auto statement = db.cached("SELECT COUNT(*) FROM " + table);
      statement->step();
      return statement->column_int64(0);
    }
    pqxx::connection connection(database_url_);
    pqxx::nontransaction work(connection);
    return work.exec("SELECT COUNT(*) FROM " + table)[0][0].as<int64_t>();
  }
  void exec_sql(const std::string& sql) {
    if (!postgres()) {
      Database db(dir_.path() / "keel.db");
      db.exec(sql);
      return;
    }
    pqxx::connection connection(database_url_);
    pqxx::nontransaction work(connection);
    work.exec(sql);
  }
  proto::Mission make_mission(const std::string& name = "bridge-01") {
    proto::MissionRequest request;
    request.name = name;
    request.bundle_blob = store_->put_blob("bundle of " + name);
    return store_->create_mission(request);
  }
  proto::JobRequest job_request(const proto::Mission& mission,
                                std::vector<std::string> stages = {"ingest", "refine", "map"}) {
    proto::JobRequest request;
    request.mission_id = mission.id;
    request.stages = std::move(stages);
    return request;
  }
  proto::Lease lease(const std::string& worker = "host:1", int lease_seconds = 30) {
    auto lease = store_->lease_job({worker, lease_seconds});
    if (!lease) throw std::runtime_error("expected a job to lease");
    return *lease;
  }

  TempDir dir_;
  FakeClock clock_;
  std::string database_url_;  // PostgreSQL only
  std::unique_ptr<Store> store_;
};

}  // namespace keel::storage::testing

// Runs every TEST_P of `suite` (a StoreTest fixture) against SQLite and PostgreSQL.
#define KEEL_STORE_TEST_SUITE(suite)                                                        \
  INSTANTIATE_TEST_SUITE_P(Stores, suite,                                                   \
                           ::testing::Values(::keel::storage::testing::Backend::kSqlite,    \
                                             ::keel::storage::testing::Backend::kPostgres), \
                           ::keel::storage::testing::backend_name)
