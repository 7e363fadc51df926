// HTTPS end to end with a test CA: keel submit --wait and keel fetch over TLS, an external
// keel-worker leasing over TLS, the server's own workers on their loopback listener, a long
// poll and an event stream over TLS; clients refuse another CA's certificate, a certificate
// for another host name and the system CAs for a private CA; the server refuses TLS 1.1.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>

#include "core/sha256.h"
#include "tests/e2e/cluster.h"
#include "tests/e2e/test_ca.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class Tls : public ::testing::Test {
 protected:
  void SetUp() override {
    RunResult version;
    try {
      version = run_command({"openssl", "version"}, 10s);
    } catch (const std::exception&) {
    }
    if (version.exit_code != 0) GTEST_SKIP() << "no openssl command (deploy/setup.sh installs it)";
    ca_ = make_test_ca(root_.path() / "pki", "keel-test-ca");
    other_ca_ = make_test_ca(root_.path() / "pki", "other-ca");
    cert_ = make_server_cert(ca_, root_.path() / "pki", "server", {"DNS:localhost"});
  }

  std::vector<std::string> tls_args() const {
    return {"--tls-cert", cert_.cert.string(), "--tls-key", cert_.key.string()};
  }
  // The server's URL with the name its certificate carries.
  static std::string localhost_url(const Cluster& cluster) {
    return std::regex_replace(cluster.url(), std::regex("127\\.0\\.0\\.1"), "localhost");
  }
  client::ApiClient client(const std::string& url, const std::string& token,
                           const std::string& ca_file) {
    client::ClientConfig config;
    config.url = url;
    config.token = token;
    config.ca_file = ca_file;
    config.timeout_s = 20;
    return client::ApiClient(config);
  }

  TempDir root_;
  TestCa ca_, other_ca_;
  ServerCert cert_;
};

TEST_F(Tls, ClientsVerifyTheServerAndRefuseAnyOtherCertificate) {
  Cluster cluster(root_.path(), /*workers=*/0, 0, tls_args());
  ASSERT_EQ(cluster.url().rfind("https://127.0.0.1:", 0), 0u) << cluster.url();
  const std::string url = localhost_url(cluster);
  auto trusted = client(url, cluster.token(), ca_.cert.string());
  EXPECT_EQ(trusted.request("GET", "/v1/jobs").status, 200);

  auto expect_refused = [&](const std::string& target_url, const std::string& ca_file,
                            const std::string& expected) {
    auto api = client(target_url, cluster.token(), ca_file);
    try {
      api.request("GET", "/v1/jobs");
      ADD_FAILURE() << target_url << " with CA '" << ca_file << "' was accepted";
    } catch (const client::ApiCallError& e) {
      EXPECT_EQ(e.status(), 0);
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  expect_refused(url, other_ca_.cert.string(), "certificate is not trusted");
  expect_refused(url, "", "certificate is not trusted");  // the system CAs do not know it
  // The certificate names localhost, not 127.0.0.1.
  expect_refused(cluster.url(), ca_.cert.string(), "certificate is not trusted");
  // Plain HTTP on the HTTPS port gets no answer; the server stays up.
  auto plain =
      client(std::regex_replace(cluster.url(), std::regex("https"), "http"), cluster.token(), "");
  EXPECT_THROW(plain.request("GET", "/v1/jobs"), client::ApiCallError);
  EXPECT_EQ(trusted.request("GET", "/healthz").status, 200);

  // The CLI: the same refusal, and success with --ca-file / KEEL_CA_FILE.
  std::vector<std::string> env = {"KEEL_URL=" + url, "KEEL_TOKEN=" + cluster.token(),
                                  "XDG_CACHE_HOME=" + (root_.path() / "cache").string()};
  RunResult refused = run_command({Programs().cli.string(), "jobs"}, 60s, env);
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_NE(refused.output.find("certificate is not trusted"), std::string::npos) << refused.output;
  RunResult listed =
      run_command({Programs().cli.string(), "--ca-file", ca_.cert.string(), "jobs"}, 60s, env);
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  env.push_back("KEEL_CA_FILE=" + ca_.cert.string());
  listed = run_command({Programs().cli.string(), "jobs"}, 60s, env);
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
}

TEST_F(Tls, TheServerRefusesTls11AndServesLongPollsAndEventStreams) {
  Cluster cluster(root_.path(), /*workers=*/0, 0, tls_args());
  const std::string port = cluster.url().substr(cluster.url().rfind(':') + 1);
  const fs::path request = root_.path() / "events.http";
  std::ofstream(request) << "GET /v1/events HTTP/1.1\r\nHost: localhost\r\nAuthorization: Bearer "
                         << cluster.token() << "\r\n\r\n";
  // openssl s_client as an independent TLS client; `timeout` ends the kept-open stream.
  const std::vector<std::string> s_client = {
      "timeout",     "3",         "openssl", "s_client",        "-connect", "127.0.0.1:" + port,
      "-servername", "localhost", "-CAfile", ca_.cert.string(), "-quiet"};
  std::vector<std::string> events = {"sh", "-c", ""};
  for (const auto& arg : s_client) events[2] += "'" + arg + "' ";
  events[2] += "< '" + request.string() + "'";
  const RunResult stream = run_command(events, 20s);
  EXPECT_NE(stream.output.find("HTTP/1.1 200 OK"), std::string::npos) << stream.output;
  EXPECT_NE(stream.output.find("text/event-stream"), std::string::npos) << stream.output;
  EXPECT_NE(stream.output.find("event: hello"), std::string::npos) << stream.output;

  std::string old = "";
  for (const auto& arg : {"timeout", "10", "openssl", "s_client", "-connect"})
    old += std::string(arg) + " ";
  const RunResult tls11 = run_command(
      {"sh", "-c", old + "127.0.0.1:" + port + " -tls1_1 -cipher DEFAULT@SECLEVEL=0 < /dev/null"},
      20s);
  EXPECT_NE(tls11.exit_code, 0) << tls11.output;
  const RunResult tls12 =
      run_command({"sh", "-c",
                   old + "127.0.0.1:" + port + " -tls1_2 -CAfile " + ca_.cert.string() +
                       " -servername localhost < /dev/null"},
                  20s);
  EXPECT_EQ(tls12.exit_code, 0) << tls12.output;
  EXPECT_NE(tls12.output.find("Verify return code: 0 (ok)"), std::string::npos) << tls12.output;

  // A long poll (Response::pending) over TLS answers 204 at its deadline.
  auto api = client(localhost_url(cluster), cluster.token(), ca_.cert.string());
  const auto start = std::chrono::steady_clock::now();
  const auto answer = api.request("POST", "/v1/worker/lease",
                                  R"({"worker":"probe","lease_seconds":5,"wait_seconds":1})");
  EXPECT_EQ(answer.status, 204);
  EXPECT_GE(std::chrono::steady_clock::now() - start, 900ms);
}

TEST_F(Tls, SubmitWaitAndFetchOverHttpsWithExternalAndLocalWorkers) {
  const fs::path mission = root_.path() / "mission";
  simulate_mission(mission, 5, "imu,dvl,depth");
  const std::vector<std::string> worker_token_cmd = {"--data-dir"};
  Cluster cluster(root_.path(), /*workers=*/0, 0, tls_args());
  const std::string url = localhost_url(cluster);

  // An external keel-worker with a worker token, over TLS.
  const RunResult made =
      run_command({Programs().server.string(), "--data-dir", cluster.data_dir().string(), "token",
                   "create", "--project", "*", "--role", "worker"},
                  60s);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(made.output, match, std::regex("[0-9a-f]{64}")));
  Process worker({Programs().worker.string(), "serve", "--server", url, "--token", match.str(),
                  "--ca-file", ca_.cert.string(), "--poll-seconds", "0.2", "--cache-dir",
                  (root_.path() / "worker-cache").string()},
                 root_.path() / "worker.log");

  const std::vector<std::string> env = {"KEEL_URL=" + url, "KEEL_TOKEN=" + cluster.token(),
                                        "KEEL_CA_FILE=" + ca_.cert.string(),
                                        "XDG_CACHE_HOME=" + (root_.path() / "cache").string()};
  auto submit = [&](const std::string& name) {
    const RunResult r = run_command({Programs().cli.string(), "submit", mission.string(), "--name",
                                     name, "--stages", "ingest", "--wait", "-q"},
                                    300s, env);
    EXPECT_EQ(r.exit_code, 0) << r.output << "\nworker log:\n"
                              << read_file(root_.path() / "worker.log");
    std::smatch id;
    EXPECT_TRUE(std::regex_search(r.output, id, std::regex("j_[0-9a-f]+"))) << r.output;
    return id.str();
  };
  const std::string job = submit("over-tls");
  const fs::path out = root_.path() / "out";
  const RunResult fetched =
      run_command({Programs().cli.string(), "fetch", job, "-o", out.string(), "-q"}, 120s, env);
  ASSERT_EQ(fetched.exit_code, 0) << fetched.output;
  auto api = client(url, cluster.token(), ca_.cert.string());
  const auto artifacts = api.list_artifacts(job);
  ASSERT_FALSE(artifacts.empty());
  for (const auto& artifact : artifacts)
    EXPECT_EQ(keel::sha256_file(out / artifact.name), artifact.sha256) << artifact.name;
  worker.signal(SIGTERM);
  worker.wait_for(30s);

  // The server's own workers use their loopback listener (plain HTTP, 127.0.0.1 only).
  Cluster local(root_.path() / "local", /*workers=*/1, 0, tls_args());
  const std::vector<std::string> local_env = {
      "KEEL_URL=" + localhost_url(local), "KEEL_TOKEN=" + local.token(),
      "KEEL_CA_FILE=" + ca_.cert.string(), "XDG_CACHE_HOME=" + (root_.path() / "cache2").string()};
  const RunResult r = run_command(
      {Programs().cli.string(), "submit", mission.string(), "--stages", "ingest", "--wait", "-q"},
      300s, local_env);
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

}  // namespace
}  // namespace keel::e2e
