// `keel-server token create | list | revoke` on a data folder, with and without the server
// running, and the worker token the server gives its local workers.
#include <gtest/gtest.h>

#include <regex>

#include "storage/store.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

using namespace std::chrono_literals;

RunResult token_command(const std::filesystem::path& data_dir, std::vector<std::string> args) {
  std::vector<std::string> argv = {Programs().server.string(), "--data-dir", data_dir.string(),
                                   "token"};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_command(argv, 60s);
}

// The clear token: the last line of the output that is 64 hex digits.
std::string token_in(const std::string& output) {
  std::smatch match;
  const std::regex line("(^|\n)([0-9a-f]{64})\n");
  return std::regex_search(output, match, line) ? match[2].str() : "";
}

TEST(TokenCommand, CreateListRevokeOnAStoppedServersFolder) {
  TempDir dir;
  const auto data = dir.path() / "data";
  const int64_t before = storage::system_clock_ms();
  RunResult made = token_command(data, {"create", "--project", "harbour", "--role", "submitter",
                                        "--expires", "30d", "--label", "field laptop"});
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const std::string token = token_in(made.output);
  ASSERT_EQ(token.size(), 64u) << made.output;

  std::string id;
  {
    auto store = storage::open_sqlite_store(data);
    const auto info = store->check_token(token);
    ASSERT_TRUE(info);
    EXPECT_EQ(info->role, proto::Role::kSubmitter);
    EXPECT_EQ(info->project, "harbour");
    EXPECT_EQ(info->label, "field laptop");
    const int64_t thirty_days_ms = 30LL * 86400 * 1000;
    EXPECT_GE(info->expires_at_ms, before + thirty_days_ms);
    EXPECT_LE(info->expires_at_ms, storage::system_clock_ms() + thirty_days_ms);
    id = info->id;
  }

  RunResult list = token_command(data, {"list"});
  ASSERT_EQ(list.exit_code, 0) << list.output;
  EXPECT_TRUE(std::regex_search(list.output, std::regex(id + " +submitter +harbour +active")))
      << list.output;
  EXPECT_EQ(list.output.find(token), std::string::npos) << "list never shows a clear token";

  RunResult revoked = token_command(data, {"revoke", id});
  ASSERT_EQ(revoked.exit_code, 0) << revoked.output;
  EXPECT_FALSE(storage::open_sqlite_store(data)->check_token(token));
  list = token_command(data, {"list"});
  EXPECT_TRUE(std::regex_search(list.output, std::regex(id + " +submitter +harbour +revoked")))
      << list.output;

  RunResult unknown = token_command(data, {"revoke", "t_nosuchtoken"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.output.find("token t_nosuchtoken not found"), std::string::npos)
      << unknown.output;
  RunResult bad_role = token_command(data, {"create", "--project", "p", "--role", "root"});
  EXPECT_EQ(bad_role.exit_code, 2);
  EXPECT_NE(bad_role.output.find("unknown role 'root'"), std::string::npos) << bad_role.output;
  RunResult star_viewer = token_command(data, {"create", "--project", "*", "--role", "viewer"});
  EXPECT_EQ(star_viewer.exit_code, 2);
  EXPECT_NE(star_viewer.output.find("only for admin and worker tokens"), std::string::npos)
      << star_viewer.output;
  RunResult bad_expiry =
      token_command(data, {"create", "--project", "p", "--role", "viewer", "--expires", "soon"});
  EXPECT_EQ(bad_expiry.exit_code, 2);
  EXPECT_NE(bad_expiry.output.find("duration 'soon'"), std::string::npos) << bad_expiry.output;
}

TEST(TokenCommand, ARunningServerTakesANewTokenAtOnceAndItsWorkersHoldAWorkerToken) {
  TempDir dir;
  Cluster cluster(dir.path(), /*workers=*/1);
  // The local workers' token: a worker token of every project, not the admin token.
  const std::string worker_token = read_file(cluster.data_dir() / "worker-token");
  ASSERT_EQ(worker_token.size(), 64u);
  EXPECT_NE(worker_token, cluster.token());

  RunResult made =
      token_command(cluster.data_dir(), {"create", "--project", "dock", "--role", "viewer"});
  ASSERT_EQ(made.exit_code, 0) << made.output;
  client::ClientConfig config;
  config.url = cluster.url();
  config.token = token_in(made.output);
  client::ApiClient viewer(config);
  EXPECT_EQ(viewer.request("GET", "/v1/jobs").status, 200);
  EXPECT_EQ(viewer.request("POST", "/v1/jobs", "{}").status, 403);

  config.token = worker_token;
  client::ApiClient worker(config);
  EXPECT_EQ(worker.request("GET", "/v1/jobs").status, 403) << "a worker lists no jobs";
  EXPECT_EQ(
      worker.request("POST", "/v1/worker/lease", R"({"worker":"probe","lease_seconds":5})").status,
      204);

  // A restart keeps the worker token (the file and the store agree).
  cluster.stop_server();
  cluster.start_server();
  EXPECT_EQ(read_file(cluster.data_dir() / "worker-token"), worker_token);
}

}  // namespace
}  // namespace keel::e2e
