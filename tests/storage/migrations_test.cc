#include "storage/migrations.h"

#include <gtest/gtest.h>

#include "storage/sqlite_db.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

int64_t count_rows(Database& db, const std::string& table) {
  auto statement = db.cached("SELECT COUNT(*) FROM " + table);
  statement->step();
  return statement->column_int64(0);
}

TEST(Migrations, FreshDatabaseGetsEveryMigration) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  EXPECT_EQ(schema_version(db), 0);
  const int newest = static_cast<int>(sqlite_migrations().size());
  EXPECT_EQ(apply_migrations(db, sqlite_migrations()), newest);
  EXPECT_EQ(schema_version(db), newest);
  for (const char* table : {"blobs", "uploads", "missions", "jobs", "stage_outputs", "artifacts",
                            "job_logs", "api_tokens"})
    EXPECT_EQ(count_rows(db, table), 0) << table;
}

TEST(Migrations, ReopenAppliesOnlyMissingOnesAndKeepsData) {
  testing::TempDir dir;
  const std::vector<Migration> v1 = {{1, "t", "CREATE TABLE t (x INTEGER)"}};
  std::vector<Migration> v2 = v1;
  // Re-running migration 1 would fail ("table t already exists"), so success shows it was skipped.
  v2.push_back({2, "u", "CREATE TABLE u (y INTEGER); INSERT INTO u VALUES (7)"});
  {
    Database db(dir.path() / "keel.db");
    EXPECT_EQ(apply_migrations(db, v1), 1);
    db.exec("INSERT INTO t VALUES (42)");
  }
  {
    Database db(dir.path() / "keel.db");
    EXPECT_EQ(apply_migrations(db, v1), 1);  // nothing to do
    EXPECT_EQ(apply_migrations(db, v2), 2);
    EXPECT_EQ(count_rows(db, "t"), 1);
    EXPECT_EQ(count_rows(db, "u"), 1);
  }
}

TEST(Migrations, FailedMigrationLeavesPreviousVersion) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  const std::vector<Migration> broken = {
      {1, "t", "CREATE TABLE t (x INTEGER)"},
      {2, "half", "CREATE TABLE half (y INTEGER); INSERT INTO no_such_table VALUES (1)"}};
  try {
    apply_migrations(db, broken);
    FAIL() << "expected the second migration to fail";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("migration 2 (half)"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(schema_version(db), 1);
  // The failed migration's first statement was rolled back with it.
  auto statement = db.cached("SELECT COUNT(*) FROM sqlite_master WHERE name = 'half'");
  statement->step();
  EXPECT_EQ(statement->column_int64(0), 0);
}

TEST(Migrations, NewerDatabaseIsRefused) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  apply_migrations(db, {{1, "a", "CREATE TABLE a (x)"}, {2, "b", "CREATE TABLE b (x)"}});
  EXPECT_THROW(apply_migrations(db, {{1, "a", "CREATE TABLE a (x)"}}), std::runtime_error);
}

TEST(Migrations, StoreReopenKeepsDataAndVersion) {
  testing::TempDir dir;
  std::string mission_id;
  {
    auto store = open_sqlite_store(dir.path());
    proto::MissionRequest request{"pier-3", store->put_blob("tar bytes"), "", ""};
    mission_id = store->create_mission(request).id;
  }
  auto store = open_sqlite_store(dir.path());
  EXPECT_EQ(store->get_mission(mission_id).name, "pier-3");
  Database db(dir.path() / "keel.db");
  EXPECT_EQ(schema_version(db), static_cast<int>(sqlite_migrations().size()));
  auto statement = db.cached("SELECT COUNT(*) FROM schema_version");
  statement->step();
  EXPECT_EQ(statement->column_int64(0), 1);
}

TEST(SqliteDb, TransactionRollsBackUnlessCommitted) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  db.exec("CREATE TABLE t (x INTEGER)");
  {
    Transaction transaction(db);
    db.exec("INSERT INTO t VALUES (1)");
  }  // no commit
  EXPECT_EQ(count_rows(db, "t"), 0);
  {
    Transaction transaction(db);
    auto insert = db.cached("INSERT INTO t VALUES (?1)");
    insert->bind_int64(1, 5).run();
    transaction.commit();
  }
  EXPECT_EQ(count_rows(db, "t"), 1);
}

TEST(SqliteDb, PragmasAndTypedColumns) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  auto mode = db.cached("PRAGMA journal_mode");
  ASSERT_TRUE(mode->step());
  EXPECT_EQ(mode->column_text(0), "wal");
  auto keys = db.cached("PRAGMA foreign_keys");
  ASSERT_TRUE(keys->step());
  EXPECT_EQ(keys->column_int64(0), 1);
  auto row = db.cached("SELECT ?1, ?2, ?3, ?4");
  row->bind_int64(1, int64_t{1} << 40).bind_double(2, 0.25).bind_text(3, std::string("a\0b", 3));
  row->bind_text_or_null(4, "");
  ASSERT_TRUE(row->step());
  EXPECT_EQ(row->column_int64(0), int64_t{1} << 40);
  EXPECT_EQ(row->column_double(1), 0.25);
  EXPECT_EQ(row->column_text(2), std::string("a\0b", 3));
  EXPECT_TRUE(row->column_is_null(3));
}

TEST(SqliteDb, ErrorsNameFileAndSql) {
  testing::TempDir dir;
  Database db(dir.path() / "keel.db");
  try {
    db.cached("SELECT * FROM missing_table");
    FAIL() << "expected a prepare error";
  } catch (const SqliteError& error) {
    const std::string text = error.what();
    EXPECT_NE(text.find("keel.db"), std::string::npos) << text;
    EXPECT_NE(text.find("missing_table"), std::string::npos) << text;
  }
}

}  // namespace
}  // namespace keel::storage
