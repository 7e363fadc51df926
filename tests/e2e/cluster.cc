#include "tests/e2e/cluster.h"

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>

namespace keel::e2e {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

Cluster::Cluster(const fs::path& root, int workers, int port, std::vector<std::string> server_args)
    : root_(root), workers_(workers), port_(port), server_args_(std::move(server_args)) {
  fs::create_directories(data_dir());
  start_server();
}

void Cluster::start_server() {
  fs::remove(data_dir() / "server.url");
  const std::string listen = "127.0.0.1:" + std::to_string(port_);
  std::vector<std::string> argv{Programs().server.string(), "--data-dir", data_dir().string(), "--listen",
                                listen, "--workers", std::to_string(workers_), "--worker-lease-seconds", "2"};
  argv.insert(argv.end(), server_args_.begin(), server_args_.end());
  server_ = std::make_unique<Process>(argv, root_ / ("server-" + std::to_string(starts_++) + ".log"));
  if (!wait_for_file(data_dir() / "server.url", 20s))
    throw std::runtime_error("keel-server did not start; see " + (root_ / "server-*.log").string());
  url_ = read_file(data_dir() / "server.url");
  while (!url_.empty() && (url_.back() == '\n' || url_.back() == ' ')) url_.pop_back();
}

void Cluster::kill_server() {
  server_->signal(SIGKILL);
  server_->wait_for(10s);
}

void Cluster::stop_server() {
  server_->signal(SIGTERM);
  if (!server_->wait_for(30s)) throw std::runtime_error("keel-server ignored SIGTERM for 30 s");
}

Process& Cluster::start_worker(double lease_seconds) {
  const auto index = extra_workers_.size();
  extra_workers_.push_back(std::make_unique<Process>(
      std::vector<std::string>{Programs().worker.string(), "serve", "--server", url_, "--token-file",
                               (data_dir() / "token").string(), "--lease-seconds",
                               std::to_string(static_cast<int>(lease_seconds)), "--poll-seconds", "0.2",
                               "--cache-dir", (root_ / ("worker-cache-" + std::to_string(index))).string()},
      root_ / ("worker-" + std::to_string(index) + ".log")));
  return *extra_workers_.back();
}

std::string Cluster::token() const {
  std::string token = read_file(data_dir() / "token");
  while (!token.empty() && (token.back() == '\n' || token.back() == ' ')) token.pop_back();
  return token;
}

std::vector<std::string> Cluster::cli_env() const {
  return {"KEEL_URL=" + url_, "KEEL_TOKEN=" + token(), "XDG_CACHE_HOME=" + (root_ / "cache").string()};
}

RunResult Cluster::keel(const std::vector<std::string>& args, int timeout_s) const {
  std::vector<std::string> argv = {Programs().cli.string()};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_command(argv, std::chrono::seconds(timeout_s), cli_env());
}

client::ApiClient Cluster::api() const {
  client::ClientConfig config;
  config.url = url_;
  config.token = token();
  return client::ApiClient(config);
}

int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof(address);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    ::close(fd);
    throw std::runtime_error("cannot find a free port");
  }
  ::close(fd);
  return ntohs(address.sin_port);
}

void simulate_mission(const fs::path& out, double duration_s, const std::string& sensors) {
  const RunResult result =
      run_command({Programs().sim.string(), "--scenario", "usv-bridge", "--seed", "3", "--duration",
                   std::to_string(duration_s), "--sensors", sensors, "--out", out.string()},
                  std::chrono::seconds(600));
  if (result.exit_code != 0) throw std::runtime_error("keel-sim failed: " + result.output);
}

proto::Job wait_job(client::ApiClient& api, const std::string& job_id,
                    const std::function<bool(const proto::Job&)>& done, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  proto::Job job = api.get_job(job_id);
  while (!done(job) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
    job = api.get_job(job_id);
  }
  return job;
}

}  // namespace keel::e2e
