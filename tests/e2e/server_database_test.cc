// keel-server --database: a store that cannot be opened ends the program before it listens,
// with a message naming what is wrong and an exit code saying why (server/main.cc kExit*);
// a good URL gives replicas that share one database.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cctype>
#include <fstream>

#include <pqxx/pqxx>

#include "client/api_client.h"
#include "storage/pg_migrations.h"
#include "tests/e2e/cluster.h"
#include "tests/e2e/process.h"
#include "tests/storage/pg_test_server.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Exit codes of keel-server (server/main.cc, docs/deploy.md).
constexpr int kBadUrl = 3;
constexpr int kUnreachable = 4;
constexpr int kSchemaTooNew = 5;
constexpr int kFolderNotWritable = 6;

class ServerDatabaseTest : public ::testing::Test {
 protected:
  RunResult start_expecting_failure(const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {
        Programs().server, "--data-dir", (dir_.path() / "data"), "--listen", "127.0.0.1:0",
        "--workers",       "0"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    RunResult result = run_command(argv, 30s);
    // Never half-started: it did not get as far as announcing a URL.
    EXPECT_FALSE(fs::exists(dir_.path() / "data" / "server.url")) << result.output;
    return result;
  }
  static bool mentions(const RunResult& result, const std::string& text) {
    return result.output.find(text) != std::string::npos;
  }

  TempDir dir_;
};

TEST_F(ServerDatabaseTest, UnknownSchemeIsRefused) {
  const RunResult result = start_expecting_failure({"--database", "mysql://root@db/keel"});
  EXPECT_EQ(result.exit_code, kBadUrl) << result.output;
  EXPECT_TRUE(mentions(result, "postgresql://")) << result.output;
}

TEST_F(ServerDatabaseTest, UnreachableDatabaseIsRefusedWithoutItsPassword) {
  const RunResult result =
      start_expecting_failure({"--database", "postgresql://keel:secret@127.0.0.1:1/keel"});
  EXPECT_EQ(result.exit_code, kUnreachable) << result.output;
  EXPECT_TRUE(mentions(result, "127.0.0.1:1")) << result.output;
  EXPECT_FALSE(mentions(result, "secret")) << result.output;
}

class ServerOnPostgresTest : public ServerDatabaseTest {
 protected:
  void SetUp() override {
    pg_ = testing::PgTestServer::shared();
    if (!pg_) GTEST_SKIP() << testing::PgTestServer::reason();
    url_ = pg_->create_database("keel_server");
  }
  testing::PgTestServer* pg_ = nullptr;
  std::string url_;
};

TEST_F(ServerOnPostgresTest, MissingDatabaseIsUnreachable) {
  const RunResult result = start_expecting_failure({"--database", pg_->url("no_such_db")});
  EXPECT_EQ(result.exit_code, kUnreachable) << result.output;
  EXPECT_TRUE(mentions(result, "no_such_db")) << result.output;
}

TEST_F(ServerOnPostgresTest, NewerSchemaIsRefused) {
  const int newest = static_cast<int>(storage::pg_migrations().size());
  {
    pqxx::connection connection(url_);
    pqxx::nontransaction work(connection);
    work.exec("CREATE TABLE schema_version (version integer NOT NULL)");
    work.exec("INSERT INTO schema_version VALUES (" + std::to_string(newest + 7) + ")");
  }
  const RunResult result = start_expecting_failure({"--database", url_});
  EXPECT_EQ(result.exit_code, kSchemaTooNew) << result.output;
  EXPECT_TRUE(mentions(result, "schema version " + std::to_string(newest + 7))) << result.output;
}

TEST_F(ServerOnPostgresTest, UnwritableBlobFolderIsRefused) {
  // A blob folder below a regular file can never be made (root or not).
  const fs::path file = dir_.path() / "not-a-folder";
  std::ofstream(file) << "x";
  const RunResult result =
      start_expecting_failure({"--database", url_, "--blob-dir", (file / "blobs").string()});
  EXPECT_EQ(result.exit_code, kFolderNotWritable) << result.output;
  EXPECT_TRUE(mentions(result, (file / "blobs").string())) << result.output;
}

// Two replicas on one database and one blob folder: what one is told, the other knows.
TEST_F(ServerOnPostgresTest, TwoReplicasShareOneDatabase) {
  const fs::path blobs = dir_.path() / "shared-blobs";
  auto start = [&](const std::string& name) {
    const fs::path data = dir_.path() / name;
    auto process = std::make_unique<Process>(
        std::vector<std::string>{Programs().server, "--data-dir", data, "--listen", "127.0.0.1:0",
                                 "--workers", "0", "--database", url_, "--blob-dir", blobs},
        dir_.path() / (name + ".log"));
    EXPECT_TRUE(wait_for_file(data / "server.url", 30s))
        << read_file(dir_.path() / (name + ".log"));
    return process;
  };
  auto a = start("a");
  auto b = start("b");
  // The first replica made the first token; the second found one and made none.
  const std::string token = read_file(dir_.path() / "a" / "token");
  ASSERT_FALSE(token.empty());
  EXPECT_FALSE(fs::exists(dir_.path() / "b" / "token"));
  auto client = [&](const std::string& name) {
    client::ClientConfig config;
    config.url = read_file(dir_.path() / name / "server.url");
    while (!config.url.empty() && std::isspace(static_cast<unsigned char>(config.url.back())))
      config.url.pop_back();
    config.token = token;
    while (!config.token.empty() && std::isspace(static_cast<unsigned char>(config.token.back())))
      config.token.pop_back();
    return std::make_unique<client::ApiClient>(config);
  };
  auto api_a = client("a");
  auto api_b = client("b");
  const fs::path bundle = dir_.path() / "bundle.bin";
  std::ofstream(bundle) << "not a real bundle, only bytes to store";
  const std::string sha = api_a->upload_file(bundle, dir_.path() / "state");
  const auto blob = api_b->request("GET", "/v1/blobs/" + sha);
  EXPECT_EQ(blob.status, 200) << "replica b sees the blob replica a stored";
  EXPECT_TRUE(fs::exists(blobs / "blobs")) << "blobs live in the shared folder";
}

}  // namespace
}  // namespace keel::e2e
