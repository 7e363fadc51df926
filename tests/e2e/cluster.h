// A Keel deployment on loopback for end-to-end tests: keel-server (optionally with local
// workers), extra keel-worker processes, and the `keel` CLI, all real executables.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "client/api_client.h"
#include "tests/e2e/process.h"
#include "tests/temp_dir.h"

namespace keel::e2e {

struct Programs {
  std::filesystem::path server = KEEL_SERVER_BIN;
  std::filesystem::path worker = KEEL_WORKER_BIN;
  std::filesystem::path cli = KEEL_CLI_BIN;
  std::filesystem::path sim = KEEL_SIM_BIN;
};

using keel::testing::TempDir;

class Cluster {
 public:
  // `port` 0 = ephemeral. The data folder survives restarts of the server.
  // `server_args` are added to keel-server's command line (--tls-cert F, ...).
  Cluster(const std::filesystem::path& root, int workers, int port = 0,
          std::vector<std::string> server_args = {});

  void start_server();
  void kill_server();  // SIGKILL: no chance to clean up
  void stop_server();  // SIGTERM and wait
  Process& start_worker(double lease_seconds);

  const std::string& url() const { return url_; }
  std::string token() const;
  std::filesystem::path data_dir() const { return root_ / "data"; }
  std::vector<std::string> cli_env() const;
  RunResult keel(const std::vector<std::string>& args, int timeout_s = 300) const;
  client::ApiClient api() const;

 private:
  std::filesystem::path root_;
  int workers_;
  int port_;
  std::vector<std::string> server_args_;
  std::string url_;
  std::unique_ptr<Process> server_;
  std::vector<std::unique_ptr<Process>> extra_workers_;
  int starts_ = 0;
};

// A free loopback TCP port (bound and released; fine for tests on one machine).
int free_port();
// Writes a usv-bridge mission with keel-sim; `sensors` as keel-sim's --sensors.
void simulate_mission(const std::filesystem::path& out, double duration_s,
                      const std::string& sensors);
// Polls GET /v1/jobs/{id} until `done(job)` or the timeout; returns the last job seen.
proto::Job wait_job(client::ApiClient& api, const std::string& job_id,
                    const std::function<bool(const proto::Job&)>& done, double timeout_s);

}  // namespace keel::e2e
